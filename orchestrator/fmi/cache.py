"""Built FMUs on disk, and a case's system through them.

:func:`ensure_fmus` returns the FMU files of a folder, building those that are missing or whose
variables differ from the contract (built by an older version); :func:`system_from_case` gives
the gear-shaft FMU and the four bearing FMUs of a case behind the master's interfaces.
"""

from __future__ import annotations

from pathlib import Path

from bearing_fmu import fmu_name
from fmu_src import description
from orchestrator.fmi.bearings import FmuBearings
from orchestrator.fmi.structure import FmuStructure

__all__ = ["DEFAULT_FMU_DIR", "ensure_fmus", "system_from_case"]

#: where ``gsb run`` builds and finds its FMUs unless told otherwise
DEFAULT_FMU_DIR = Path("build") / "fmus"


def ensure_fmus(names, fmu_dir=None) -> dict[str, Path]:
    """Paths of the named FMUs in ``fmu_dir`` (default ``build/fmus``), building those that are
    missing or whose variables differ from the contract (built by an older version)."""
    from fmpy import read_model_description

    from fmu_src.build import FMUS, build_fmus

    fmu_dir = Path(DEFAULT_FMU_DIR if fmu_dir is None else fmu_dir)
    paths, stale = {}, []
    for name in names:
        if name not in FMUS:
            raise ValueError(f"unknown FMU {name!r}; available: {', '.join(FMUS)}")
        path = fmu_dir / f"{name}.fmu"
        paths[name] = path
        expected = [(v.name, v.causality) for v in FMUS[name].variables]
        try:
            md = read_model_description(str(path))
            current = [(v.name, v.causality) for v in md.modelVariables]
        except Exception:  # missing or unreadable: build it
            current = None
        if current != expected:
            stale.append(name)
    if stale:
        build_fmus(fmu_dir, stale)
    return paths


def system_from_case(case, model: str | None = None, fmu_dir=None):
    """(FmuStructure, FmuBearings) of a case: the gear-shaft FMU built from the case's values
    and four instances of the bearing FMU of ``model`` (default ``bearings.model``), taken from
    ``fmu_dir`` (default ``build/fmus``; built there if missing or stale)."""
    model = case["bearings.model"] if model is None else model
    bearing_fmu = fmu_name(model)
    paths = ensure_fmus(["GearShaft", bearing_fmu], fmu_dir)
    structure = FmuStructure(paths["GearShaft"], case=case)
    try:
        bearings = FmuBearings([paths[bearing_fmu]] * 4, description.bearing_parameters(case),
                               description.bearing_speeds(case))
    except Exception:
        structure.close()
        raise
    return structure, bearings
