"""Seconds from launching ``gsb run`` to its first coupled step (warm numba cache).

Usage: ``python benchmarks/startup.py [--repeat N] [--bearing MODEL] [--fmu]``

Starts a fresh interpreter N times (default 3) running ``gsb run baguet2010_spur --periods 1``
(in-process unless ``--fmu``) in an empty folder, and prints, per run and as the median: the
imports, the master built (case, structure with its tooth-stiffness table, bearings), the
static solution with the end of initialisation (modal damping), and the first step's start
(after the time-step and unbalance checks and the results file), each as seconds since the
launch (the parent's clock before the process starts). A first run after a code
change compiles the numba kernels: run it once before quoting the figures.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time

CHILD = """
import json, sys, time
t0 = float(sys.argv[1])
marks = {"interpreter": time.time() - t0}
from orchestrator.cli import main
import orchestrator.run.runner as run
from orchestrator.coupling.master import Master
marks["imports"] = time.time() - t0
build, step, init = run.build_master, Master.step, Master.exit_initialization

def timed_build(*a, **k):
    m = build(*a, **k)
    marks["master built"] = time.time() - t0
    return m

def timed_init(self):
    init(self)
    marks["static solution + init"] = time.time() - t0

def timed_step(self, t, dt):
    if "first step" not in marks:
        marks["first step"] = time.time() - t0
    return step(self, t, dt)

run.build_master, Master.step, Master.exit_initialization = timed_build, timed_step, timed_init
code = main(sys.argv[2:])
marks["exit"] = time.time() - t0
print(json.dumps(marks))
sys.exit(code)
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--bearing", default="hybrid")
    parser.add_argument("--fmu", action="store_true", help="through the FMUs")
    args = parser.parse_args()
    runs = []
    for _ in range(args.repeat):
        with tempfile.TemporaryDirectory() as tmp:
            cmd = ["run", "baguet2010_spur", "--periods", "1", "--bearing", args.bearing,
                   "--no-figures", "--quiet", "--out", tmp]
            if not args.fmu:
                cmd.append("--in-process")
            t0 = time.time()
            proc = subprocess.run([sys.executable, "-c", CHILD, repr(t0), *cmd], cwd=tmp,
                                  capture_output=True, text=True)
            if proc.returncode != 0:
                sys.exit(f"gsb run failed: {proc.stderr[-2000:]}")
            runs.append(json.loads(proc.stdout.strip().splitlines()[-1]))
    where = "FMUs" if args.fmu else "in-process"
    print(f"gsb run baguet2010_spur --periods 1 --bearing {args.bearing} ({where}), "
          f"seconds since launch, {args.repeat} runs:")
    for key in runs[0]:
        values = [r[key] for r in runs]
        print(f"  {key:24s} median {statistics.median(values):6.2f}   "
              + " ".join(f"{v:6.2f}" for v in values))


if __name__ == "__main__":
    main()
