"""Probe of tests/system/test_fmu_run.py, run in a fresh interpreter: the FMUs a case's
bearing set loads for two bearing models."""

from __future__ import annotations

from tests.probes import dispatch, probes_of


def bearing_fmu_files(fmu_dir: str) -> dict:
    """Per model (hybrid, lumped), the file names of the FMUs of the spur case's bearings."""
    from fmu_src.case import load_case
    from orchestrator.coupling.fmi import system_from_case

    case = load_case("baguet2010_spur")
    out = {}
    for model in ("hybrid", "lumped"):
        st, b = system_from_case(case.with_overrides({"bearings.*.model": model}), fmu_dir)
        out[model] = sorted({s.path.name for s in b.slaves})
        b.close()
        st.close()
    return out


PROBES = probes_of(bearing_fmu_files)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
