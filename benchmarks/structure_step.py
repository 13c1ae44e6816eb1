"""Microseconds per Newmark step of the paper's two-shaft model with four affine bearing laws.

Usage: ``python benchmarks/structure_step.py [--steps N]``

The paper's structure (:func:`fmu_src.examples.paper_structure`: two shafts, the distributed
mesh element of the Table 1 pair) with bearings Kb = 1e8 N/m, Cb = 1e5 N s/m isotropic plus a
cross-coupled part; T = 220 N m, omega = 325 rad/s, e_mu = 0.6 mm, dt = mesh period / 32 (paper
Sec. 4). Prints the total per step (no timers) and the split mesh update / assembly (right-hand
side, bearing terms, back-substitution) / condensed solve (timers on).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from fmu_src.examples import paper_structure


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=5000)
    args = parser.parse_args()
    t0 = time.perf_counter()
    st = paper_structure()
    t_build = time.perf_counter() - t0
    mesh = st.mesh
    name = f"gear_fmu.mesh.element.MeshElement ({mesh.n_lines} x {mesh.n_slices} slices)"
    kb = np.broadcast_to(1e8 * np.eye(2), (4, 2, 2)) + np.array([[0.0, 3e7], [-2e7, 0.0]])
    cb = np.broadcast_to(1e5 * np.eye(2), (4, 2, 2)) + np.array([[0.0, 1e4], [1e4, 0.0]])
    kb, cb = kb.copy(), cb.copy()
    f0 = np.zeros((4, 2))
    st.static(f0, kb, cb)
    dt = st.mesh_period / 32
    for _ in range(500):  # warm-up (numba, caches)
        st.step(dt, f0, kb, cb)
    n = args.steps
    iters = 0
    t0 = time.perf_counter()
    for _ in range(n):
        iters += st.step(dt, f0, kb, cb).iterations
    total = (time.perf_counter() - t0) / n * 1e6
    st.timing = {"mesh": 0.0, "assembly": 0.0, "solve": 0.0}
    for _ in range(n):
        st.step(dt, f0, kb, cb)
    split = {k: v / n * 1e6 for k, v in st.timing.items()}
    print(f"mesh: {name}; {st.x.size} free DOFs condensed onto 20; build {t_build * 1e3:.0f} ms")
    print(f"{total:.1f} us per Newmark step (mean {iters / n:.2f} linear solves per step, "
          f"{n} steps after 500 warm-up)")
    print("split with timers on: " + ", ".join(f"{k} {v:.1f} us" for k, v in split.items()))


if __name__ == "__main__":
    main()
