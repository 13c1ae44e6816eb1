"""Parallel efficiency of the Fig. 8 sweep on Dask: one process vs a 2-worker LocalCluster.

Usage: ``python benchmarks/sweep_efficiency.py [--periods N] [--speeds K]``

The Fig. 8 sweep (spur case, speeds 100-1200 rad/s, hybrid and linear bearings) run twice over
the same points: serially in this process (``scheduler="none"``), then on a LocalCluster of two
single-threaded worker processes. Prints both wall times and the parallel efficiency
``T_serial / (2 T_cluster)`` (target >= 80 %). Each configuration is warmed up first (numba
kernels compiled and cached on disk, so the workers load them).
"""

from __future__ import annotations

import argparse
import os
import tempfile

import numpy as np

from orchestrator.sweeps.runner import SweepPoint, run_sweep

CASE = "baguet2010_spur"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--periods", type=int, default=256, help="mesh periods per point")
    parser.add_argument("--speeds", type=int, default=12, help="speeds from 100 to 1200 rad/s")
    args = parser.parse_args()
    speeds = np.linspace(100.0, 1200.0, args.speeds)
    points = [SweepPoint({"drive.speed": float(w)}, m, f"{m} {w:g}")
              for m in ("hybrid", "linear") for w in speeds]
    print(f"{len(points)} points (Fig. 8: {args.speeds} speeds x hybrid, linear), "
          f"{args.periods} mesh periods each; {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as tmp:
        warm = points[:1] + points[-1:]
        run_sweep(CASE, warm, f"{tmp}/warm.h5", 2, scheduler="none", progress=False)
        serial = run_sweep(CASE, points, f"{tmp}/serial.h5", args.periods,
                           scheduler="none", progress=False)
        print(f"one process:               {serial.wall_time:7.1f} s")
        run_sweep(CASE, warm, f"{tmp}/warm2.h5", 2, n_workers=2, progress=False)
        cluster = run_sweep(CASE, points, f"{tmp}/cluster.h5", args.periods, n_workers=2,
                            progress=False)
        print(f"LocalCluster, 2 workers:   {cluster.wall_time:7.1f} s (cluster start included)")
    eff = serial.wall_time / (2 * cluster.wall_time)
    speedup = serial.wall_time / cluster.wall_time
    print(f"parallel efficiency: {100 * eff:.0f} %  (speed-up {speedup:.2f})")
    if serial.failed or cluster.failed:
        print(f"failed points: {serial.failed} {cluster.failed}")


if __name__ == "__main__":
    main()
