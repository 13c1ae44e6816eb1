"""The FMUs driven through fmpy, behind the same master interface as
:mod:`orchestrator.coupling.inprocess`.

* :mod:`~orchestrator.coupling.fmi.instance`: one instantiated FMU with its log
  (:class:`~orchestrator.coupling.fmi.instance.FmuInstance`);
* :mod:`~orchestrator.coupling.fmi.bearings`: the bearing FMUs as a BearingSet
  (:class:`~orchestrator.coupling.fmi.bearings.FmuBearings`);
* :mod:`~orchestrator.coupling.fmi.structure`: the gear-shaft FMU as a StructureSlave
  (:class:`~orchestrator.coupling.fmi.structure.FmuStructure`, rollback with
  :class:`~orchestrator.coupling.fmi.structure.FmuState`);
* :mod:`~orchestrator.coupling.fmi.cache`: built FMUs on disk and a case's system through them;
* :mod:`~orchestrator.coupling.fmi.steps`: their part of the coupled step
  (:func:`orchestrator.coupling.step.coupled_steps`), the FMI functions called from compiled
  code (:mod:`~orchestrator.coupling.fmi.calls`).
"""

from orchestrator.coupling.fmi.bearings import FmuBearings
from orchestrator.coupling.fmi.cache import (
    default_fmu_dir,
    ensure_fmus,
    system_from_case,
    system_from_files,
)
from orchestrator.coupling.fmi.instance import FmuError, FmuInstance
from orchestrator.coupling.fmi.structure import FmuState, FmuStructure

__all__ = [
    "FmuBearings",
    "FmuError",
    "FmuInstance",
    "FmuState",
    "FmuStructure",
    "default_fmu_dir",
    "ensure_fmus",
    "system_from_case",
    "system_from_files",
]
