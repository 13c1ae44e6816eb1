"""Microseconds per call of the four hybrid bearings of the paper's case, on the run's own states.

Usage: ``python benchmarks/bearing_set.py [--steps N] [--repeat N] [--threads N]``

Runs the paper's spur case in-process (hybrid bearings, the master's Python loop) for
``--steps`` steps after its static solution and records the journal states of every bearing
evaluation (static solution included). Then replays them through fresh bearings of the case
(:class:`bearing_fmu.hybrid.model.HybridSet`, warm starts carried from call to call as in the
run) in one compiled loop of ``hybrid_set_global`` calls: no Python, no structure step in
between, so that the figure moves with the bearing kernels only (the whole run's share of the
bearings is in ``paper_case.py --breakdown``). Prints the best of ``--repeat`` replays in µs
per set call, and the Newton passes on t and active-set passes per bearing call, for the first
evaluation of each step (its warm start is the accepted state of the step before) and the later
ones (the calls of the static solution apart). ``--threads N`` replays the same calls through
``hybrid_set_threads`` on N threads as well (``gsb run --threads``; one compiled call per set
call, as in the run), and checks that every output is the one thread's.
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
from orchestrator.coupling.master import BearingSet
from orchestrator.coupling.system import build_master


@njit
def replay_threads(states, active, ws, iws, trig, coef, q, omega, clearance, fs, res, status,
                   journal, out, outs):
    """:func:`replay` through ``hybrid_set_threads`` (the thread count numba's, set by
    ``kernel_arguments``), without the passes. Returns the first failing call or -1."""
    for k in range(journal.shape[0]):
        b, _ = hk.hybrid_set_threads(states, active, ws, iws, trig, coef, q, omega, clearance,
                                     fs, res, status, journal[k], out)
        if b >= 0:
            return k
        outs[k] = out
    return -1


@njit
def replay(states, active, ws, iws, trig, coef, q, omega, clearance, fs, res, journal, out,
           outs, t_passes, lcp_passes):
    """One ``hybrid_set_global`` call per row of ``journal`` (calls, nb, 4), each call's output
    into ``outs`` (calls, nb, 5, 2); the passes of each bearing call into ``t_passes``,
    ``lcp_passes`` (calls, nb). Returns the first failing call or -1."""
    for k in range(journal.shape[0]):
        b, _ = hk.hybrid_set_global(states, active, ws, iws, trig, coef, q, omega, clearance,
                                    fs, res, journal[k], out)
        if b >= 0:
            return k
        outs[k] = out
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
    case = load_case("baguet2010_spur", {"bearings.*.model": "hybrid"})
    master = build_master(case, in_process=True)
    # the bearings called back in Python (BearingSet's default group): every evaluation of
    # the coupled step passes through evaluate(), the same numbers
    master.bearings.compiled_groups = lambda: BearingSet.compiled_groups(master.bearings)
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


def fresh_arguments(threads: int = 1) -> tuple:
    """The arguments of ``hybrid_set_global`` (``hybrid_set_threads`` on more than one
    thread) for new bearings of the paper's case."""
    case = load_case("baguet2010_spur", {"bearings.*.model": "hybrid"})
    bearings = ModelBearings(description.bearing_models(case), description.bearing_frames(case),
                             description.bearing_speeds(case))
    (hybrid,) = bearings.hybrid_sets  # the paper's four hybrid bearings: one set
    if threads > 1 and hybrid.use_threads(threads) != threads:
        raise SystemExit(f"--threads {threads}: numba cannot give the bearings threads here")
    return hybrid.kernel_arguments()


def best_replay(replayer, threads: int, repeat: int, journal, out, *per_call) -> float:
    """The best of ``repeat`` replays of ``journal`` [s] by ``replayer`` (:func:`replay` or
    :func:`replay_threads`), each through fresh bearings; ``per_call`` the arrays it fills
    call by call."""
    replayer(*fresh_arguments(threads), journal[:2], out,
             *(a[:2] for a in per_call))  # compiles
    best = float("inf")
    for _ in range(repeat):
        arguments = fresh_arguments(threads)
        t0 = time.perf_counter()
        failed = replayer(*arguments, journal, out, *per_call)
        best = min(best, time.perf_counter() - t0)
        if failed >= 0:
            raise SystemExit(f"the replay failed at call {failed}: the recorded run did not")
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=3000, help="steps of the recorded run")
    parser.add_argument("--repeat", type=int, default=10, help="timed replays (best kept)")
    parser.add_argument("--threads", type=int, default=1,
                        help="also replay through the set on this many threads")
    args = parser.parse_args()
    journal, kinds = record(args.steps)
    nb = journal.shape[1]
    out = np.empty((nb, 5, 2))
    t_passes = np.zeros(journal.shape[:2], dtype=np.int64)
    lcp_passes = np.zeros_like(t_passes)
    serial = np.empty((len(journal), nb, 5, 2))
    best = best_replay(replay, 1, args.repeat, journal, out, serial, t_passes, lcp_passes)
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
    if args.threads > 1:
        outs = np.empty_like(serial)
        threaded = best_replay(replay_threads, args.threads, args.repeat, journal, out, outs)
        same = np.array_equal(outs, serial)
        print(f"on {args.threads} threads: {threaded / len(journal) * 1e6:.2f} us per set call "
              f"({best / threaded:.2f} x one thread's); every output "
              f"{'the same bits' if same else 'DIFFERENT'}")
        if not same:
            raise SystemExit("the threads' outputs differ from one thread's")


if __name__ == "__main__":
    main()
