"""Probe of tests/orchestrator/analysis/test_run_report.py: the report of a run through the
FMUs (run in the test's process)."""

from __future__ import annotations

import numpy as np

from tests.probes import dispatch, probes_of


def fmu_report(out_dir: str, fmu_dir: str) -> dict:
    """The spur case with linear bearings over 8 mesh periods through the FMUs: the report's
    numbers as stored in the results file, and the same quantities from its data."""
    from fmu_src.case import load_case
    from orchestrator.run.results import read_results
    from orchestrator.run.runner import run_case

    case = load_case("baguet2010_spur", {"bearings.*.model": "linear",
                                         "simulation.mesh_periods": 8})
    s = run_case(case, out_dir=out_dir, fmu_dir=fmu_dir, progress=False)
    r = read_results(s.results)
    a = r["attrs"]
    fb = np.hypot(r["bearing_force"][128:, :, 0], r["bearing_force"][128:, :, 1])
    return {
        "mode": a["mode"], "steps": len(r["time"]), "R": float(a["dynamic_factor"][0]),
        "max_mesh": float(r["mesh_force"][128:].max()),
        "ptp": a["bearing_force_ptp"].tolist(), "ptp_data": np.ptp(fb, axis=0).tolist(),
        "lines": np.nan_to_num(a["line_amplitudes"], nan=-1.0).tolist(),
        "labels": [str(x) for x in a["line_labels"]],
        "summary_R": float(s.report["dynamic_factor"][0])}


PROBES = probes_of(fmu_report)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
