"""Wall time of the paper's spur case (Table 4): 2048 mesh periods, 65,536 steps.

Usage: ``python benchmarks/paper_case.py [--periods N] [--skip-fmu] [--contact-location]``

Runs, in one process and in this order: hybrid bearings in-process, the linear 8-coefficient
model in-process (Table 4 case 0), hybrid through the FMUs (fmpy), and prints wall time,
steps/s, bearing evaluations (= Reynolds solves for the film models), coupled iterations per
step, and the ratios. ``--contact-location`` adds hybrid in-process runs of the spur and
helical cases with ``simulation.locate_contact`` off (the steps not cut at the contact events,
:mod:`gear_fmu.structure`) and the ratio of the default (on) to them. The numba kernels are
compiled before the clock starts (a 2-period warm-up run per configuration). The paper needed
8 minutes for case 2 in 2010.
"""

from __future__ import annotations

import argparse
import platform
import tempfile

from fmu_src.case import load_case
from orchestrator.run import run_case

CASE = "baguet2010_spur"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--periods", type=int, default=2048)
    parser.add_argument("--skip-fmu", action="store_true")
    parser.add_argument("--contact-location", action="store_true",
                        help="also time the runs with simulation.locate_contact off")
    args = parser.parse_args()
    configs = [("hybrid", True), ("linear", True)]
    if not args.skip_fmu:
        configs.append(("hybrid", False))
    if args.contact_location:
        configs += [("hybrid", True, "no-location"), ("hybrid", True, "helical"),
                    ("hybrid", True, "helical-no-location")]
    print(f"machine: {platform.machine()}, CPython {platform.python_version()}; {CASE}, "
          f"{args.periods} mesh periods ({args.periods * 32} steps)")
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        for model, in_process, *variant in configs:
            kw = dict(bearing=model, in_process=in_process, out_dir=tmp, progress=False,
                      figures=False)
            name = variant[0] if variant else ""
            run = load_case("baguet2010_helical" if "helical" in name else CASE,
                            {"simulation.locate_contact": "no-location" not in name})
            run_case(run, periods=2, **kw)  # warm-up: numba, FMU extraction
            s = run_case(run, periods=args.periods, **kw)
            label = f"{model:7s} {'in-process' if in_process else 'FMUs (fmpy)'} {name}"
            rows[(model, in_process, *variant)] = s
            solves = 4 * s.bearing_evaluations
            print(f"{label:24s} {s.wall_time:7.1f} s  {s.steps_per_second:7.0f} steps/s  "
                  f"{s.iterations_per_step:5.2f} it/step  {solves:9d} bearing evaluations  "
                  f"static {s.static_time * 1e3:.0f} ms")
    ref = rows[("hybrid", True)].wall_time
    print(f"linear / hybrid (in-process): {rows[('linear', True)].wall_time / ref:.2f}")
    if ("hybrid", False) in rows:
        print(f"FMU / in-process (hybrid): {rows[('hybrid', False)].wall_time / ref:.2f}")
    if args.contact_location:
        off = rows[("hybrid", True, "no-location")].wall_time
        print(f"spur: contact location on / off: {ref / off:.3f}")
        h_on = rows[("hybrid", True, "helical")].wall_time
        h_off = rows[("hybrid", True, "helical-no-location")].wall_time
        print(f"helical: contact location on / off: {h_on / h_off:.3f}")


if __name__ == "__main__":
    main()
