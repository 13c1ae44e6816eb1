"""Microseconds per master cycle through the gear-shaft FMU vs the in-process structure.

Usage: ``python benchmarks/fmu_overhead.py [--steps N] [--fmu PATH]``

Builds ``GearShaft.fmu`` into a temporary folder (unless ``--fmu`` names one) and drives the
paper's spur case (the shipped ``baguet2010_spur``) two ways with the same affine bearing laws
(Kb 1e8 N/m with a cross-coupled part, Cb 1e4 N s/m, dt = mesh period / 32):

* ``FmuStructure`` (:mod:`orchestrator.coupling.fmi`): fmi2SetReal of the 56 law inputs, fmi2DoStep,
  fmi2GetReal of the 16 journal outputs; fmi2GetFMUstate + fmi2SetFMUstate (+ free);
* ``InProcessStructure`` (the same master interface on the in-process structure):
  ``set_bearing_laws`` + ``do_step`` + ``journal_states``; ``get_state`` + ``set_state``.

Prints µs per cycle (best of 5 blocks, after warm-up), the per-call cost of the FMI layer alone
(set + get with no step, state get/set), and the FMU's share of a cycle.

Then the bearing side: the four hybrid bearings of the case after its static solution, through
their FMUs (``FmuBearings``, FMUs from the per-user cache) and in-process (``ModelBearings``),
evaluated at journal states that move by about 1e-7 m from call to call as in a run (a
repeated state would find the hybrid solver's warm start exact). Best of 5 alternating blocks.
"""

from __future__ import annotations

import argparse
import tempfile
import time

import numpy as np

from bearing_fmu.affine import AffineLaws
from fmu_src.examples import paper_structure
from orchestrator.coupling.fmi import FmuStructure
from orchestrator.coupling.inprocess import InProcessStructure


def laws() -> AffineLaws:
    kb = np.broadcast_to(1e8 * np.eye(2), (4, 2, 2)) + np.array([[0.0, 3e7], [-2e7, 0.0]])
    cb = np.broadcast_to(1e4 * np.eye(2), (4, 2, 2)).copy()
    return AffineLaws(np.zeros((4, 2)), kb.copy(), cb)


def best_us(fn, n: int, blocks: int = 5) -> float:
    best = float("inf")
    for _ in range(blocks):
        t0 = time.perf_counter()
        fn(n)
        best = min(best, (time.perf_counter() - t0) / n)
    return best * 1e6


def measure(slave, law, dt: float, n: int) -> dict:
    slave.set_bearing_laws(law)
    slave.solve_static()
    slave.exit_initialization()
    clock = {"t": 0.0}
    state0 = slave.get_state()

    def cycle(k):
        for _ in range(k):
            slave.set_bearing_laws(law)
            slave.do_step(clock["t"], dt)
            slave.journal_states()
            clock["t"] += dt

    def io_only(k):
        for _ in range(k):
            slave.set_bearing_laws(law)
            slave.journal_states()

    def state(k):
        for _ in range(k):
            s = slave.get_state()
            slave.set_state(s)

    cycle(200)  # warm-up (numba, caches)
    out = {"cycle": best_us(cycle, n)}
    out["io"] = best_us(io_only, n)
    out["state"] = best_us(state, n)
    slave.set_state(state0)
    return out


def bearing_sets(n: int) -> tuple[float, float]:
    """µs per evaluation of the four bearings (FMUs, in-process), best of 5 alternating blocks."""
    from fmu_src.case import load_case
    from orchestrator.coupling.system import build_master

    case = load_case("baguet2010_spur")
    masters = [build_master(case, in_process=flag) for flag in (False, True)]
    try:
        for m in masters:
            m.solve_static()
        base = masters[1].laws.states
        rng = np.random.default_rng(0)
        moves = 1e-7 * rng.standard_normal((200, 4, 4)) * [1.0, 1.0, 0.0, 0.0]
        states = [base + d for d in moves]
        best = [float("inf"), float("inf")]
        for _ in range(5):
            for i, m in enumerate(masters):
                t0 = time.perf_counter()
                for k in range(n):
                    m.bearings.evaluate(states[k % 200])
                best[i] = min(best[i], (time.perf_counter() - t0) / n * 1e6)
        return best[0], best[1]
    finally:
        for m in masters:
            m.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1000, help="cycles per timed block")
    parser.add_argument("--fmu", help="a built GearShaft.fmu (default: build one)")
    args = parser.parse_args()
    law = laws()
    with tempfile.TemporaryDirectory(prefix="gsb_bench_") as tmp:
        path = args.fmu
        if path is None:
            from fmu_src.build.fmus import build_fmus

            path = build_fmus(tmp, ["GearShaft"])[0]
        ref = InProcessStructure(paper_structure())
        dt = ref.structure.mesh_period / 32
        inproc = measure(ref, law, dt, args.steps)
        fmu = FmuStructure(path)
        try:
            viafmu = measure(fmu, law, dt, args.steps)
        finally:
            fmu.close()
    rows = [("setReal laws + doStep + getReal journal", "cycle"),
            ("set laws + read journal, no step", "io"),
            ("state get + set", "state")]
    print(f"{'µs per call':44s} {'FMU':>9s} {'in-process':>11s} {'FMU - in-process':>17s}")
    for label, key in rows:
        a, b = viafmu[key], inproc[key]
        print(f"{label:44s} {a:9.1f} {b:11.1f} {a - b:17.1f}")
    share = (viafmu["cycle"] - inproc["cycle"]) / viafmu["cycle"]
    print(f"FMI layer share of an FMU cycle: {100 * share:.1f} %")
    a, b = bearing_sets(args.steps)
    print(f"{'four hybrid bearings, moving states':44s} {a:9.1f} {b:11.1f} {a - b:17.1f}")
    print(f"bearing FMUs / in-process: {a / b:.2f}")


if __name__ == "__main__":
    main()
