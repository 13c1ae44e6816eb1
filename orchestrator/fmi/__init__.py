"""The FMUs driven through fmpy, behind the same master interface as :mod:`orchestrator.inprocess`.

* :mod:`~orchestrator.fmi.instance`: one instantiated FMU with its log
  (:class:`~orchestrator.fmi.instance.FmuInstance`);
* :mod:`~orchestrator.fmi.bearings`: the bearing FMUs as a BearingSet
  (:class:`~orchestrator.fmi.bearings.FmuBearings`);
* :mod:`~orchestrator.fmi.structure`: the gear-shaft FMU as a StructureSlave
  (:class:`~orchestrator.fmi.structure.FmuStructure`, rollback with
  :class:`~orchestrator.fmi.structure.FmuState`);
* :mod:`~orchestrator.fmi.cache`: built FMUs on disk and a case's system through them.
"""

from orchestrator.fmi.bearings import FmuBearings
from orchestrator.fmi.cache import (
    default_fmu_dir,
    ensure_fmus,
    system_from_case,
    system_from_files,
)
from orchestrator.fmi.instance import FmuError, FmuInstance
from orchestrator.fmi.structure import FmuState, FmuStructure

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
