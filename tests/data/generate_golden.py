"""Record golden trajectories for tests/test_golden.py (run from the repository root).

A fixture pins the journal trajectories of the paper's spur case (hybrid bearings, 4 mesh
periods = 128 steps, in-process and through the FMUs) as computed by a named commit, so that a
refactor, or speed work (issue 13), can show it changes no result (1e-12 relative). Re-record
only for a change that is meant to move results, and say so in the commit message.

Two fixtures:

* ``golden_spur_hybrid.json``: the time-integration refinements off (``consistent_start``,
  ``locate_contact`` false), recorded at 34318c3 by an earlier version of this script; kept as
  it is (the refinements-off path must still give it);
* ``golden_spur_hybrid_default.json``: the shipped case as it runs by default (refinements on),
  recorded by this script before the speed work of issue 13.

Each is computed in a fresh interpreter with an empty numba cache folder (``NUMBA_CACHE_DIR``):
the last digits of the fastmath kernels depend on whether numba compiled a kernel's callees in
the same process or loaded them from its cache (LLVM optimises across the calls only in the
first case; measured: 2e-12 on positions, 2e-10 on velocities over these 128 steps), so the
fixture is the all-fresh compilation and ``tests/test_golden.py`` compiles the same way. Both
transports run one after the other in that interpreter, as the test runs them.

Usage: ``python tests/data/generate_golden.py COMMIT`` (COMMIT: the commit the code is at).
"""

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
PERIODS = 4


def main(commit: str) -> None:
    out = {"commit": commit, "case": "baguet2010_spur", "bearing": "hybrid", "periods": PERIODS,
           "settings": "the shipped case's defaults (consistent_start, locate_contact on)",
           "note": "journal [s, t, s_dot, t_dot] of bearings 1-4 at every step, m and m/s"}
    code = f"""
import json, sys, tempfile
sys.path.insert(0, {str(ROOT)!r})
import numpy as np
from tests.helpers import run_paper_case
out = {{}}
with tempfile.TemporaryDirectory() as tmp:
    for transport in ("in-process", "fmu"):
        r, s = run_paper_case(tmp + "/" + transport, periods={PERIODS},
                              in_process=transport == "in-process", fmu_dir=tmp + "/fmus")
        journal = np.concatenate([r["journal_position"], r["journal_velocity"]], axis=2)
        out[transport] = {{"time": r["time"].tolist(), "journal": journal.tolist(),
                          "static": s.static_positions.tolist()}}
print(json.dumps(out))
"""
    with tempfile.TemporaryDirectory() as tmp:
        env = {**os.environ, "NUMBA_CACHE_DIR": tmp + "/numba"}
        res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             check=True, cwd=tmp, env=env)
    out |= json.loads(res.stdout.strip().splitlines()[-1])
    (HERE / "golden_spur_hybrid_default.json").write_text(json.dumps(out) + "\n")


if __name__ == "__main__":
    main(sys.argv[1])
