"""What never losing results costs: the flushes and resume checkpoints of a run's file.

Runs the paper's spur case (hybrid bearings) in-process and through FMUs, with the results
writer instrumented: number of flushes (one per second of wall time), time spent in them
(rows, HDF5 flush, checkpoint of the coupled state) and the checkpoint's size; the share of the
run's wall time they take. Usage::

    python benchmarks/results_writer.py [--periods 256] [--skip-fmu]
"""

from __future__ import annotations

import argparse
import tempfile

from paper_case import timed_calls  # this folder: benchmarks/paper_case.py

from fmu_src.case import load_case
from orchestrator.coupling.master import Master
from orchestrator.run.runner import run_case


def measure(in_process: bool, periods: int) -> dict:
    counts: dict[str, int] = {}
    sizes = []
    targets = [("flush", "orchestrator.run.results.ResultsWriter", "flush"),
               ("checkpoint", "orchestrator.coupling.master.Master", "checkpoint")]
    original = Master.checkpoint

    def sized(self):  # the checkpoint's size, recorded by the wrapped call
        state = original(self)
        sizes.append(len(state))
        return state

    Master.checkpoint = sized
    try:
        with tempfile.TemporaryDirectory() as tmp, timed_calls(targets, counts) as totals:
            case = load_case("baguet2010_spur", {"simulation.mesh_periods": periods})
            s = run_case(case, in_process=in_process, out_dir=tmp, progress=False,
                         echo_warnings=False)
    finally:
        Master.checkpoint = original
    return {"flushes": counts.get("flush", 0), "flush_s": totals.get("flush", 0.0),
            "checkpoint_s": totals.get("checkpoint", 0.0), "bytes": sizes[-1] if sizes else 0,
            "wall_s": s.wall_time, "steps": s.steps}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--periods", type=int, default=256)
    parser.add_argument("--skip-fmu", action="store_true")
    args = parser.parse_args()
    print(f"paper spur case, hybrid bearings, {args.periods} mesh periods")
    print(f"{'transport':<11} {'steps':>6} {'run [s]':>8} {'flushes':>7} {'flush [ms]':>10} "
          f"{'of which checkpoint [ms]':>24} {'checkpoint [kB]':>15} {'share of run':>12}")
    for in_process in (True, False) if not args.skip_fmu else (True,):
        m = measure(in_process, args.periods)
        n = max(m["flushes"], 1)
        print(f"{'in-process' if in_process else 'FMUs':<11} {m['steps']:>6} {m['wall_s']:>8.2f} "
              f"{m['flushes']:>7} {1e3 * m['flush_s'] / n:>10.2f} "
              f"{1e3 * m['checkpoint_s'] / n:>24.2f} {m['bytes'] / 1e3:>15.1f} "
              f"{100 * m['flush_s'] / m['wall_s']:>11.2f} %")


if __name__ == "__main__":
    main()
