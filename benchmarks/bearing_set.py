"""Microseconds per call of the four hybrid bearings of the paper's case, on the run's own states.

Usage: ``python benchmarks/bearing_set.py [--steps N] [--repeat N]``

Runs the paper's spur case in-process (hybrid bearings, the master's Python loop) for
``--steps`` steps after its static solution and records the journal states of every bearing
evaluation (static solution included). Then replays them through fresh bearings of the case
(:class:`bearing_fmu.hybrid.model.HybridSet`, warm starts carried from call to call as in the
run) in one compiled loop of ``hybrid_set_global`` calls: no Python, no structure step in
between, so that the figure moves with the bearing kernels only (the whole run's share of the
bearings is in ``paper_case.py --breakdown``). Prints the best of ``--repeat`` replays in µs
per set call, and the Newton passes on t and active-set passes per bearing call, for the first
evaluation of each step (its warm start is the accepted state of the step before) and the later
ones (the calls of the static solution apart).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from numba import njit

from bearing_fmu.hybrid import _kernels as hk
from fmu_src import description
from fmu_src.case import load_case
from fmu_src.description import time_step
from orchestrator.coupling.inprocess import ModelBearings
from orchestrator.coupling.system import build_master


@njit
def replay(states, active, ws, iws, trig, coef, q, omega, clearance, fs, res, journal, out,
           t_passes, lcp_passes):
    """One ``hybrid_set_global`` call per row of ``journal`` (calls, nb, 4); the passes of each
    bearing call into ``t_passes``, ``lcp_passes`` (calls, nb). Returns the first failing call
    or -1."""
    for k in range(journal.shape[0]):
        b, _ = hk.hybrid_set_global(states, active, ws, iws, trig, coef, q, omega, clearance,
                                    fs, res, journal[k], out)
        if b >= 0:
            return k
        for j in range(states.shape[0]):
            t_passes[k, j] = states[j].t_iterations
            lcp_passes[k, j] = states[j].lcp_iterations
    return -1


#: what a recorded call was: of the static solution, the first of a step, a later one
STATIC, FIRST, LATER = 0, 1, 2


def record(steps: int) -> tuple[np.ndarray, np.ndarray]:
    """The journal states (calls, nb, 4) [m, m/s] of every bearing evaluation of the static
    solution and ``steps`` steps of the paper's case, and what each call was (:data:`STATIC`,
    :data:`FIRST`, :data:`LATER`)."""
    case = load_case("baguet2010_spur", {"bearings.model": "hybrid"})
    master = build_master(case, in_process=True)
    master.fused = None  # the Python loop: every evaluation passes through evaluate()
    calls, kinds = [], []
    evaluate = master.bearings.evaluate
    kind = [STATIC]

    def recorded(states):
        calls.append(np.array(states, dtype=float))
        kinds.append(kind[0])
        if kind[0] == FIRST:
            kind[0] = LATER
        return evaluate(states)

    master.bearings.evaluate = recorded
    try:
        master.solve_static()
        master.exit_initialization()
        dt = time_step(case)
        st = master.structure.physics
        for _ in range(steps):
            kind[0] = FIRST
            master.step(st.t, dt)
    finally:
        master.close()
    return np.array(calls), np.array(kinds)


def fresh_arguments() -> tuple:
    """The arguments of ``hybrid_set_global`` for new bearings of the paper's case."""
    case = load_case("baguet2010_spur", {"bearings.model": "hybrid"})
    bearings = ModelBearings(description.bearing_models(case), description.BEARING_FRAMES,
                             description.bearing_speeds(case))
    return bearings.hybrid_set.kernel_arguments()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=3000, help="steps of the recorded run")
    parser.add_argument("--repeat", type=int, default=10, help="timed replays (best kept)")
    args = parser.parse_args()
    journal, kinds = record(args.steps)
    nb = journal.shape[1]
    out = np.empty((nb, 5, 2))
    t_passes = np.zeros(journal.shape[:2], dtype=np.int64)
    lcp_passes = np.zeros_like(t_passes)
    replay(*fresh_arguments(), journal[:2], out, t_passes[:2], lcp_passes[:2])  # compiles
    best = float("inf")
    for _ in range(args.repeat):
        arguments = fresh_arguments()
        t0 = time.perf_counter()
        failed = replay(*arguments, journal, out, t_passes, lcp_passes)
        best = min(best, time.perf_counter() - t0)
        if failed >= 0:
            raise SystemExit(f"the replay failed at call {failed}: the recorded run did not")
    print(f"baguet2010_spur, {args.steps} steps: {len(journal)} calls of the {nb} hybrid "
          f"bearings, best of {args.repeat} replays: {best / len(journal) * 1e6:.2f} us per "
          "set call")
    for label, k in (("static solution", STATIC), ("first call of a step", FIRST),
                     ("later calls of a step", LATER)):
        rows = kinds == k
        if rows.any():
            print(f"  {label:23s} {int(rows.sum()):6d} set calls: "
                  f"{t_passes[rows].mean():.3f} Newton passes on t, "
                  f"{lcp_passes[rows].mean():.3f} active-set passes per bearing call")


if __name__ == "__main__":
    main()
