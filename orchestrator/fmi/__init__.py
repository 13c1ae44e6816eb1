"""The FMUs driven through fmpy, behind the same master interface as :mod:`orchestrator.inprocess`.

* :mod:`~orchestrator.fmi.instance`: one instantiated FMU with its log (:class:`FmuInstance`);
* :mod:`~orchestrator.fmi.bearings`: the bearing FMUs as a BearingSet (:class:`FmuBearings`);
* :mod:`~orchestrator.fmi.structure`: the gear-shaft FMU as a StructureSlave
  (:class:`FmuStructure`, rollback with :class:`FmuState`);
* :mod:`~orchestrator.fmi.cache`: built FMUs on disk and a case's system through them.
"""

from orchestrator.fmi.bearings import FmuBearings
from orchestrator.fmi.cache import DEFAULT_FMU_DIR, ensure_fmus, system_from_case
from orchestrator.fmi.instance import FmuError, FmuInstance
from orchestrator.fmi.structure import FmuState, FmuStructure

__all__ = [
    "DEFAULT_FMU_DIR",
    "FmuBearings",
    "FmuError",
    "FmuInstance",
    "FmuState",
    "FmuStructure",
    "ensure_fmus",
    "system_from_case",
]
