"""Built FMUs on disk, and a case's system through them.

:func:`ensure_fmus` returns the FMU files of a folder, building those that are missing or stale
(built from other code, or with other variables); by default the folder is in the per-user
cache, one per code version and interpreter (:func:`default_fmu_dir`), so runs from any
working directory share one build. Builds into one folder are serialised by a lock file: two
runs that start at once build once and both use the result. :func:`system_from_case` gives
the gear-shaft FMU and one bearing FMU instance per bearing (of the bearing's own model) of a
case behind the master's interfaces.

The gear-shaft FMU's variables are those of a gear train (its ports per bearing, mesh and gear,
its parameters per case key: :func:`fmu_src.contract.gear_variables`): for a case whose train
has the variables of the shipped paper case's, it is ``GearShaft.fmu``; for any other train,
``GearShaft_<digest>.fmu`` (:func:`gear_fmu_name`), built once for that train and carrying the
case it was first built for (its parameters set to each run's case).
"""

from __future__ import annotations

import hashlib
import logging
from pathlib import Path

from fmu_src import description
from fmu_src.contract import bearing_fmu_name, gear_variables
from fmu_src.slaves.bootstrap import locked
from orchestrator.coupling.fmi.bearings import FmuBearings
from orchestrator.coupling.fmi.structure import FmuStructure

__all__ = ["GEAR", "default_fmu_dir", "ensure_fmus", "gear_fmu_name", "system_from_case",
           "system_from_files"]

#: the name of the gear-shaft FMU among :data:`fmu_src.build.fmus.FMUS`
GEAR = "GearShaft"


def default_fmu_dir() -> Path:
    """``<user cache>/fmus/<code hash>-<interpreter key>``: where ``gsb run`` builds and finds
    its FMUs unless told otherwise (:func:`fmu_src.slaves.bootstrap.cache_dir`;
    ``GSB_CACHE_DIR`` moves it). One folder per interpreter too: an FMU's loader names the
    Python that built it (``resources/gsb_python.txt``), so an FMU built by another virtual
    environment would start that one's Python (or one removed since) in a C host."""
    from fmu_src.build.fmus import code_hash
    from fmu_src.slaves.bootstrap import cache_dir

    return cache_dir() / "fmus" / f"{code_hash()}-{interpreter_key()}"


def interpreter_key() -> str:
    """8 hex digits of the running interpreter's path and version (:func:`default_fmu_dir`)."""
    import sys

    return hashlib.sha256(f"{sys.executable}\n{sys.version}".encode()).hexdigest()[:8]


def _signature(variables) -> list[tuple]:
    return [(v.name, v.causality) for v in variables]


def gear_fmu_name(case=None) -> str:
    """The file stem of the gear-shaft FMU of ``case``'s gear train (module docstring):
    ``GearShaft`` when its variables are those of the FMU built for the shipped case (the
    paper's cases), else ``GearShaft_<12 hex digits>``, a digest of its variables' names and
    causalities."""
    if case is None:
        return GEAR
    mine = _signature(gear_variables(case))
    if mine == _signature(gear_variables()):
        return GEAR
    digest = hashlib.sha256(repr(mine).encode()).hexdigest()[:12]
    return f"{GEAR}_{digest}"


def _stale(path: Path, current_hash: str, variables) -> bool:
    from fmpy import read_model_description

    from fmu_src.build.fmus import carried_hash

    if carried_hash(path) != current_hash:
        return True
    try:
        md = read_model_description(str(path))
    except Exception:  # unreadable: build it again
        return True
    return [(v.name, v.causality) for v in md.modelVariables] != _signature(variables)


def ensure_fmus(names, fmu_dir=None, case=None) -> dict[str, Path]:
    """Paths of the named FMUs (names of :data:`fmu_src.build.fmus.FMUS`) in ``fmu_dir``
    (default :func:`default_fmu_dir`), building those that are missing or stale, under a lock
    (module docstring). ``GearShaft``: the gear-shaft FMU of ``case``'s gear train
    (:func:`gear_fmu_name`; default: the shipped case's), returned under the key
    ``"GearShaft"``."""
    from fmu_src.build.fmus import FMUS, build_fmus, code_hash

    fmu_dir = default_fmu_dir() if fmu_dir is None else Path(fmu_dir)
    for name in names:
        if name not in FMUS:
            raise ValueError(f"unknown FMU {name!r}; available: {', '.join(FMUS)}")
    gear = gear_fmu_name(case)
    paths = {name: fmu_dir / f"{gear if name == GEAR else name}.fmu" for name in names}
    wanted = {name: (gear_variables(case) if name == GEAR and gear != GEAR
                     else FMUS[name].variables) for name in names}
    current = code_hash()

    def stale() -> list[str]:
        return [n for n, p in paths.items() if _stale(p, current, wanted[n])]

    if not stale():
        return paths
    with locked(fmu_dir):
        todo = stale()  # another run built?
        if todo:
            logging.getLogger("gsb.startup").info(
                "building the FMUs %s in %s (once per code version) ...",
                ", ".join(paths[n].stem for n in todo), fmu_dir)
            build_fmus(fmu_dir, todo, case=case if gear != GEAR else None, gear_name=gear)
    return paths


def system_from_files(case, gear_fmu, bearing_fmus, bearing_parameters=None):
    """(FmuStructure, FmuBearings) from FMU files: the gear-shaft FMU (built for the case's
    gear train) with the case's structural fields as parameters and one bearing FMU per
    bearing (any file with the bearing contract, :mod:`orchestrator.coupling.fmi.bearings`;
    the layout's order) with ``bearing_parameters`` (default: the case's bearing data,
    :func:`fmu_src.description.bearing_parameters`), named after the case's bearings."""
    if bearing_parameters is None:
        bearing_parameters = description.bearing_parameters(case)
    structure = FmuStructure(gear_fmu, case=case)
    try:
        bearings = FmuBearings(bearing_fmus, bearing_parameters,
                               description.bearing_speeds(case),
                               description.layout(case).bearing_names)
    except BaseException:
        structure.close()
        raise
    return structure, bearings


def system_from_case(case, fmu_dir=None):
    """(FmuStructure, FmuBearings) of a case: the gear-shaft FMU of its gear train and one
    instance per bearing of the bearing FMU of its own model (``bearings.<name>.model``),
    from ``fmu_dir`` (default :func:`default_fmu_dir`; built there if missing or stale)."""
    names = [bearing_fmu_name(case[f"bearings.{b}.model"])
             for b in description.layout(case).bearing_names]
    paths = ensure_fmus([GEAR, *dict.fromkeys(names)], fmu_dir, case=case)
    return system_from_files(case, paths[GEAR], [paths[n] for n in names])
