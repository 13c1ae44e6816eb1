"""Re-record the golden run of tests/system/test_golden.py, on purpose (the reason goes in the
commit).

    python tests/data/generate_golden.py

(from any folder, in the environment the tests run in; about a minute on 2 cores). It writes
``tests/data/golden_spur.json`` (:mod:`tests.golden`): the paper's spur case with hybrid
bearings, in-process, over 4 mesh periods at T/32 and T/64, shipped settings and refinements
off, and the report of the whole 2048-period run at T/32 (and at T/64, to show how much
halving the step moves it). It records the commit and the versions it ran with.
"""

from __future__ import annotations

import json
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from tests.golden import (  # noqa: E402 - the repository first on the path
    FIXTURE,
    PERIODS,
    SETTINGS,
    STEPS,
    channel_tolerances,
    summary,
    summary_deviation,
    trajectories,
)
from tests.helpers import run_paper_case  # noqa: E402


def _provenance() -> dict:
    import numba
    import numpy
    import scipy

    def git(*args):
        return subprocess.run(["git", *args], capture_output=True, text=True, cwd=ROOT
                              ).stdout.strip()

    dirty = bool(git("status", "--porcelain", "--", "bearing_fmu", "gear_fmu", "fmu_src",
                     "orchestrator"))
    return {"commit": git("rev-parse", "--short", "HEAD") + (" (modified)" if dirty else ""),
            "python": platform.python_version(), "numpy": numpy.__version__,
            "scipy": scipy.__version__, "numba": numba.__version__,
            "machine": platform.machine()}


def main() -> None:
    out = {**_provenance(), "case": "baguet2010_spur", "bearing": "hybrid",
           "periods": PERIODS, "steps_per_mesh_period": list(STEPS),
           "note": "channels as the results file names them, SI units (m, m/s, N); "
                   "'runs' by setting then steps per mesh period"}
    out["runs"] = {}
    for setting, overrides in SETTINGS.items():
        runs = {str(n): trajectories(PERIODS, n, **overrides) for n in STEPS}
        tol = channel_tolerances(runs["64"], runs["32"])
        print(f"{setting}: tolerances " + ", ".join(
            f"{k} {v.min():.2e}..{v.max():.2e}" for k, v in tol.items()), flush=True)
        out["runs"][setting] = runs
    out["summary"] = {}
    for n in STEPS:
        with tempfile.TemporaryDirectory() as tmp:
            _, s = run_paper_case(tmp, periods=2048,
                                  **{"simulation.steps_per_mesh_period": n})
        out["summary"][str(n)] = summary(s.report)
        print(f"2048 periods at T/{n}: R = {s.report['dynamic_factor']:.6f}", flush=True)
    print("halving the step moves the summary by "
          f"{summary_deviation(out['summary']['64'], out['summary']['32']):.2%}")
    FIXTURE.write_text(json.dumps(out) + "\n")
    print(f"wrote {FIXTURE}")


if __name__ == "__main__":
    main()
