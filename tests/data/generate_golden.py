"""Record the golden trajectories of tests/test_golden.py (run from the repository root).

The fixture pins the journal trajectories of the paper's spur case (hybrid bearings, 4 mesh
periods = 128 steps, in-process and through the FMUs) as computed by a named commit, so that a
refactor can show it changes no result (issue 9: 1e-12 relative). Re-record only for a change
that is meant to move results, and say so in the commit message.

Each transport runs in a fresh interpreter with an empty numba cache folder
(``NUMBA_CACHE_DIR``): the last digits of the fastmath kernels depend on whether numba compiled
a kernel's callees in the same process or loaded them from its cache (LLVM optimises across
the calls only in the first case; measured: 2e-12 on positions, 2e-10 on velocities over these
128 steps), so the fixture is the all-fresh compilation and ``tests/test_golden.py`` compiles the
same way.

Usage: ``python tests/data/generate_golden.py COMMIT`` (COMMIT: the commit the code is at).
"""

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
PERIODS = 4


def main(commit: str) -> None:
    out = {"commit": commit, "case": "baguet2010_spur", "bearing": "hybrid", "periods": PERIODS,
           "note": "journal [s, t, s_dot, t_dot] of bearings 1-4 at every step, m and m/s"}
    for transport in ("in-process", "fmu"):
        code = f"""
import json, sys, tempfile
sys.path.insert(0, {str(HERE.parents[1])!r})
from orchestrator.case import load_case
from orchestrator.results import read_results
from orchestrator.run import run_case
case = load_case({str(HERE.parents[1] / 'models' / 'baguet2010_spur.toml')!r})
with tempfile.TemporaryDirectory() as tmp:
    s = run_case(case, bearing="hybrid", periods={PERIODS}, in_process={transport == 'in-process'},
                 out_dir=tmp, progress=False, figures=False, fmu_dir=tmp + "/fmus")
    r = read_results(s.results)
print(json.dumps({{"time": r["time"].tolist(), "journal": r["journal"].tolist(),
                  "static": s.static_positions.tolist()}}))
"""
        with tempfile.TemporaryDirectory() as tmp:
            env = {**os.environ, "NUMBA_CACHE_DIR": tmp + "/numba"}
            res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                 check=True, cwd=tmp, env=env)
        out[transport] = json.loads(res.stdout.strip().splitlines()[-1])
    (HERE / "golden_spur_hybrid.json").write_text(json.dumps(out) + "\n")


if __name__ == "__main__":
    main(sys.argv[1])
