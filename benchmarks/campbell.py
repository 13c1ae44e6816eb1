"""Seconds of ``gsb modal CASE --campbell`` by phase, in a fresh interpreter (warm numba cache).

Usage: ``python benchmarks/campbell.py [--repeat N] [--speeds K] [--case NAME]``

Starts a fresh interpreter N times (default 3) running ``gsb modal CASE --campbell`` with K
speeds (default 16, the command's default) in an empty folder, and prints per run and as the
median, in seconds since the launch (the parent's clock before the process starts): the
imports, the modes at the nominal speed, the Campbell data (a static solution, the damping on
Kb(X0) and the damped modes at every speed) and the figure written, then the process's end. A
first run after a code change compiles the numba kernels: run it once before quoting figures.
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
from orchestrator.analysis import campbell
import orchestrator.figures.campbell as figure
marks["imports"] = time.time() - t0
data, plot, at = (campbell.Linearisation.campbell, figure.plot_campbell,
                  campbell.Linearisation.at)

def timed_at(self, *a, **k):
    out = at(self, *a, **k)
    marks.setdefault("nominal modes", time.time() - t0)
    return out

def timed_data(self, *a, **k):
    out = data(self, *a, **k)
    marks["campbell data"] = time.time() - t0
    return out

def timed_plot(*a, **k):
    out = plot(*a, **k)
    marks["figure written"] = time.time() - t0
    return out

campbell.Linearisation.at, campbell.Linearisation.campbell, figure.plot_campbell = (
    timed_at, timed_data, timed_plot)
code = main(["modal", sys.argv[2], "--campbell", "campbell.png", "--campbell-speeds",
             sys.argv[3], "--out", "."])
marks["end"] = time.time() - t0
print(json.dumps({"code": code, "marks": marks}))
"""


def one_run(case: str, speeds: int) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.time()
        proc = subprocess.run([sys.executable, "-c", CHILD, repr(t0), case, str(speeds)],
                              capture_output=True, text=True, cwd=tmp, timeout=600)
    if proc.returncode != 0:
        sys.exit(f"gsb modal failed (exit {proc.returncode}):\n{proc.stderr[-2000:]}")
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    if out["code"] != 0:
        sys.exit(f"gsb modal returned {out['code']}:\n{proc.stderr[-2000:]}")
    return out["marks"]


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--speeds", type=int, default=16)
    p.add_argument("--case", default="baguet2010_spur")
    args = p.parse_args(argv)
    runs = [one_run(args.case, args.speeds) for _ in range(args.repeat)]
    print(f"gsb modal {args.case} --campbell, {args.speeds} speeds: seconds since the launch "
          f"(CPython {sys.version.split()[0]})")
    names = list(runs[0])
    print(f"{'phase':16s}" + "".join(f"{'run ' + str(k + 1):>9s}" for k in range(len(runs)))
          + f"{'median':>9s}")
    for name in names:
        values = [r[name] for r in runs]
        print(f"{name:16s}" + "".join(f"{v:9.2f}" for v in values)
              + f"{statistics.median(values):9.2f}")


if __name__ == "__main__":
    main()
