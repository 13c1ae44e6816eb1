"""Microseconds per Newmark step of a case's structure with affine bearing laws.

Usage: ``python benchmarks/structure_step.py [--steps N] [--case NAME]``

The structure of a shipped case (default the paper's spur case: two shafts, the distributed
mesh element of the Table 1 pair; ``two_stage_reducer``: three shafts, two meshes, six
bearings) with every bearing Kb = 1e8 N/m, Cb = 1e5 N s/m isotropic plus a cross-coupled part;
the case's torque, speed, unbalance and time step (the fastest mesh's period / 32 for the
shipped cases). Prints the total per step (:meth:`gear_fmu.structure.Structure.step`: one
compiled call, :func:`gear_fmu.step.kernel.advance_pieces`), the DOFs, the condensed DOFs and
the mesh slices; ``benchmarks/kernel_parts.py`` times the pieces of a step.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from fmu_src.case import load_case
from fmu_src.description import structure, time_step


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=5000)
    parser.add_argument("--case", default="baguet2010_spur")
    args = parser.parse_args()
    case = load_case(args.case)
    t0 = time.perf_counter()
    st = structure(case)
    t_build = time.perf_counter() - t0
    nb = st.nb
    kb = np.broadcast_to(1e8 * np.eye(2), (nb, 2, 2)) + np.array([[0.0, 3e7], [-2e7, 0.0]])
    cb = np.broadcast_to(1e5 * np.eye(2), (nb, 2, 2)) + np.array([[0.0, 1e4], [1e4, 0.0]])
    kb, cb = kb.copy(), cb.copy()
    f0 = np.zeros((nb, 2))
    st.static(f0, kb, cb)
    dt = time_step(case)
    for _ in range(500):  # warm-up (numba, the condensations of the recurring sub-steps)
        st.step(dt, f0, kb, cb)
    n = args.steps
    iters = 0
    t0 = time.perf_counter()
    for _ in range(n):
        iters += st.step(dt, f0, kb, cb).iterations
    total = (time.perf_counter() - t0) / n * 1e6
    slices = " + ".join(f"{m.n_lines} x {m.n_slices}" for m in st.meshes)
    print(f"{args.case}: {st.x.size} free DOFs condensed onto {st.nc}, {nb} bearings, "
          f"mesh slices {slices}; build {t_build * 1e3:.0f} ms")
    print(f"{total:.1f} us per Newmark step (mean {iters / n:.2f} linear solves per step, "
          f"{n} steps after 500 warm-up)")


if __name__ == "__main__":
    main()
