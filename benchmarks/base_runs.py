"""Wall time of the base runs of ``gsb reproduce``: the spur and helical cases with the
hybrid, linear and lumped-spring bearings, in-process, 2048 mesh periods each.

Usage: ``python benchmarks/base_runs.py [--periods N] [--cases spur,helical]
[--models hybrid,linear,lumped]``

Each run is what a point of the reproduce's sweeps costs on a worker (Figs. 8-11 and 16 vary
the speed, torque, unbalance and helix angle of these cases), without the sweep's own work.
Prints per run the wall time [s], steps/s and coupled iterations per step. The numba kernels
are compiled before the clock starts (a 2-period run of each configuration first).
"""

from __future__ import annotations

import argparse
import platform
import tempfile

from fmu_src.case import load_case
from orchestrator.run.runner import run_case


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--periods", type=int, default=2048)
    parser.add_argument("--cases", default="spur,helical",
                        help="comma-separated: spur, helical (baguet2010_<case>)")
    parser.add_argument("--models", default="hybrid,linear,lumped",
                        help="comma-separated bearing models")
    args = parser.parse_args()
    print(f"machine: {platform.machine()}, CPython {platform.python_version()}; "
          f"{args.periods} mesh periods ({args.periods * 32} steps) per run, in-process")
    with tempfile.TemporaryDirectory() as tmp:
        for case_name in args.cases.split(","):
            for model in args.models.split(","):
                case = load_case(f"baguet2010_{case_name}", {"bearings.*.model": model})
                for periods in (2, args.periods):  # the first: numba's warm-up
                    s = run_case(case.with_overrides({"simulation.mesh_periods": periods}),
                                 in_process=True, out_dir=tmp, progress=False, overwrite=True)
                print(f"{case_name:8s} {model:7s} {s.wall_time:7.2f} s  "
                      f"{s.steps_per_second:7.0f} steps/s  {s.iterations_per_step:5.2f} it/step")


if __name__ == "__main__":
    main()
