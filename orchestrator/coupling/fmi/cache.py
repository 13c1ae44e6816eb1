"""Built FMUs on disk, and a case's system through them.

:func:`ensure_fmus` returns the FMU files of a folder, building those that are missing or stale
(built from other code, or with other variables); by default the folder is in the per-user
cache, one per code version (:func:`default_fmu_dir`), so runs from any working directory share
one build. Builds into one folder are serialised by a lock file: two runs that start at once
build once and both use the result. :func:`system_from_case` gives the gear-shaft FMU and the
four bearing FMUs of a case behind the master's interfaces.
"""

from __future__ import annotations

import logging
from pathlib import Path

from fmu_src import description
from fmu_src.contract import bearing_fmu_name
from fmu_src.slaves.bootstrap import locked
from orchestrator.coupling.fmi.bearings import FmuBearings
from orchestrator.coupling.fmi.structure import FmuStructure

__all__ = ["default_fmu_dir", "ensure_fmus", "system_from_case", "system_from_files"]


def default_fmu_dir() -> Path:
    """``<user cache>/fmus/<code hash>``: where ``gsb run`` builds and finds its FMUs unless
    told otherwise (:func:`fmu_src.slaves.bootstrap.cache_dir`; ``GSB_CACHE_DIR`` moves it)."""
    from fmu_src.build.fmus import code_hash
    from fmu_src.slaves.bootstrap import cache_dir

    return cache_dir() / "fmus" / code_hash()


def _stale(name: str, path: Path, current_hash: str) -> bool:
    from fmpy import read_model_description

    from fmu_src.build.fmus import FMUS, carried_hash

    if carried_hash(path) != current_hash:
        return True
    try:
        md = read_model_description(str(path))
    except Exception:  # unreadable: build it again
        return True
    expected = [(v.name, v.causality) for v in FMUS[name].variables]
    return [(v.name, v.causality) for v in md.modelVariables] != expected


def ensure_fmus(names, fmu_dir=None) -> dict[str, Path]:
    """Paths of the named FMUs in ``fmu_dir`` (default :func:`default_fmu_dir`), building
    those that are missing or stale, under a lock (module docstring)."""
    from fmu_src.build.fmus import FMUS, build_fmus, code_hash

    fmu_dir = default_fmu_dir() if fmu_dir is None else Path(fmu_dir)
    for name in names:
        if name not in FMUS:
            raise ValueError(f"unknown FMU {name!r}; available: {', '.join(FMUS)}")
    paths = {name: fmu_dir / f"{name}.fmu" for name in names}
    current = code_hash()
    if not any(_stale(n, p, current) for n, p in paths.items()):
        return paths
    with locked(fmu_dir):
        stale = [n for n, p in paths.items() if _stale(n, p, current)]  # another run built?
        if stale:
            logging.getLogger("gsb.startup").info(
                "building the FMUs %s in %s (once per code version) ...", ", ".join(stale),
                fmu_dir)
            build_fmus(fmu_dir, stale)
    return paths


def system_from_files(case, gear_fmu, bearing_fmus, bearing_parameters=None):
    """(FmuStructure, FmuBearings) from FMU files: the gear-shaft FMU with the case's
    structural fields as parameters and one bearing FMU per bearing (any file with the
    bearing contract, :mod:`orchestrator.coupling.fmi.bearings`) with ``bearing_parameters``
    (default:
    the case's bearing data, :func:`fmu_src.description.bearing_parameters`)."""
    if bearing_parameters is None:
        bearing_parameters = description.bearing_parameters(case)
    structure = FmuStructure(gear_fmu, case=case)
    try:
        bearings = FmuBearings(bearing_fmus, bearing_parameters,
                               description.bearing_speeds(case))
    except BaseException:
        structure.close()
        raise
    return structure, bearings


def system_from_case(case, fmu_dir=None):
    """(FmuStructure, FmuBearings) of a case: the gear-shaft FMU and one instance per bearing
    of the bearing FMU of its own model (``bearings.<name>.model``), from ``fmu_dir`` (default
    :func:`default_fmu_dir`; built there if missing or stale)."""
    names = [bearing_fmu_name(case[f"bearings.{b}.model"]) for b in case.names("bearings")]
    paths = ensure_fmus(["GearShaft", *dict.fromkeys(names)], fmu_dir)
    return system_from_files(case, paths["GearShaft"], [paths[n] for n in names])
