"""What a run-up costs against a run at constant speed of the same steps (in-process).

Usage: ``python benchmarks/run_up.py [--periods N] [--repeat R] [--bearing MODEL]
[--gyroscopic]``

Runs the paper's spur case N mesh periods (default 512) at constant speed, then as a run-up
``ramp to 400 rad/s in T`` with T the run's length (325 -> 400 rad/s, the time step of the
highest speed for both: the constant run is given the same steps), alternating R times
(default 3), and prints the wall time per step of each and their ratio (median). A run-up
plans one step at a time (its loads change at every step) and condenses the sub-step lengths
its moving contact events make; the constant run plans blocks of up to 128 steps. With
``--gyroscopic`` both runs have the gyroscopic terms (``simulation.gyroscopic``), whose
tangent a run-up condenses again at every step's speed. The first
call compiles nothing new (warm numba cache expected: run once before quoting).
"""

from __future__ import annotations

import argparse
import statistics
import time

from fmu_src.case import load_case
from fmu_src.description import mesh_period
from orchestrator.coupling.system import build_master


def _seconds_per_step(case, steps: int, dt: float) -> float:
    master = build_master(case, in_process=True)
    try:
        master.solve_static()
        master.exit_initialization()
        t0 = time.perf_counter()
        k = 0
        while k < steps:
            block = master.steps(k, dt, min(128, steps - k))
            if block.error is not None:
                raise block.error
            k += block.count
        return (time.perf_counter() - t0) / steps
    finally:
        master.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--periods", type=int, default=512)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--bearing", default="hybrid")
    parser.add_argument("--gyroscopic", action="store_true")
    args = parser.parse_args()
    ramp = load_case("baguet2010_spur", {"bearings.*.model": args.bearing,
                                         "simulation.gyroscopic": args.gyroscopic})
    dt = mesh_period(ramp.with_overrides({"drive.speed_profile": "ramp to 400 rad/s in 1 s"}))
    dt /= ramp["simulation.steps_per_mesh_period"]
    steps = args.periods * ramp["simulation.steps_per_mesh_period"]
    up = ramp.with_overrides({"drive.speed_profile": f"ramp to 400 rad/s in {steps * dt!r} s"})
    ratios = []
    for r in range(args.repeat):
        constant = _seconds_per_step(ramp, steps, dt)
        run_up = _seconds_per_step(up, steps, dt)
        ratios.append(run_up / constant)
        print(f"repeat {r + 1}: constant {1e6 * constant:.1f} us/step, run-up "
              f"{1e6 * run_up:.1f} us/step, ratio {ratios[-1]:.2f}")
    gyroscopic = ", gyroscopic terms" if args.gyroscopic else ""
    print(f"{steps} steps of {dt:.4g} s, {args.bearing} bearings{gyroscopic}: run-up / constant = "
          f"{statistics.median(ratios):.2f} (median of {args.repeat})")


if __name__ == "__main__":
    main()
