"""Microseconds per piece of the compiled kernels of a coupled iteration (paper case states).

Usage: ``python benchmarks/kernel_parts.py [--steps N] [--calls N]``

Runs the paper's spur case in-process (hybrid bearings) for ``--steps`` steps after its static
solution, then times, each in a compiled loop of ``--calls`` calls (best of 3):

* the hybrid kernel of bearing 1 at its last state, warm (one Newton pass on t, one
  active-set pass: the cheapest call with the Jacobian), and its pieces: the element integrals
  with and without the Jacobian's weights, the axial integrals, the assembly of A and b, one
  active-set pass (Thomas factors and solve, then the test of the set), the factors and solve
  alone, one more solve with the factors;
* the structure's step pieces at the state of the last step: the right-hand side and tangent
  (:func:`gear_fmu.step.assembly.prepare_step`) at a step's first iteration and at a later one
  (the history products memoised), its history product alone, one mesh
  evaluation (all slices, tangent assembled), one Newton solve of the condensed system.

The mean cost of a call in the run (more Newton and active-set passes) is in
``paper_case.py --breakdown``; this script says what one pass of each piece costs.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from numba import njit

from bearing_fmu.hybrid import _kernels as hk
from bearing_fmu.hybrid import _lcp, _ritz, axial
from bearing_fmu.hybrid._workspace import A, B
from bearing_fmu.hybrid.axial import AXIAL_COEF
from fmu_src.case import load_case
from fmu_src.description import time_step
from gear_fmu.loads import unbalance_into
from gear_fmu.mesh.element import _mesh_kernel
from gear_fmu.step.assembly import history_memo, history_products, prepare_step
from gear_fmu.step.contact_loop import _newton_solve
from orchestrator.coupling.system import build_master


@njit
def _kernel(n, st, x, y, xd, yd, active, ws, iws, trig, coef, res):
    for _ in range(n):
        st[0].predict = False
        hk.hybrid_kernel(st, x, y, xd, yd, True, active, ws, iws, trig, coef, res)
    return st[0].t_iterations, st[0].lcp_iterations


@njit
def _elements(n, ws, trig, x, y, jac):
    delta = 2.0 * math.pi / ws.shape[1]
    for _ in range(n):
        _ritz.element_integrals(x, y, trig, ws, delta, jac)


@njit
def _axial(n, t, lam, coef, g):
    for _ in range(n):
        axial.axial_integrals(t, lam, coef, g)


@njit
def _assemble(n, g, ws):
    for _ in range(n):
        _ritz.assemble(g, ws)


@njit
def _lcp_pass(n, ws, active, iws):
    start = active.copy()
    passes = 0
    for _ in range(n):
        active[:] = start
        p, _, _ = _lcp.solve_lcp(ws, active, iws[0], iws[1], False, 8 * active.size + 20)
        passes += p
    return passes / n


@njit
def _factor_solve(n, ws, active, iws):
    for _ in range(n):
        _lcp.factor_solve(ws, active, iws[0], iws[1], ws[B], ws[A])


@njit
def _substitute(n, ws, active, iws, nr, out):
    for _ in range(n):
        _lcp.substitute(ws, active, iws[0], iws[1], nr, ws[B], out)


@njit
def _prepare(n, mc, g_t, g_const, x, v, a, f_c, unb, unb_idx, f0, kb, cb, s0, dt, ng, memo):
    for _ in range(n):
        prepare_step(mc, g_t, g_const, x, v, a, f_c, unb, unb_idx, f0, kb, cb, s0, dt, ng, memo)


@njit
def _history(n, mc, g_t, x, v, a, dt):
    nc = g_t.shape[1] - g_t.shape[0]
    no_memo = np.empty(0)
    for _ in range(n):
        history_products(mc, g_t, x, v, a, dt, nc, no_memo)


@njit
def _mesh(n, fresh, angle, q, p, geo, xi_tab, k_tab, zs, dl, n_lines, dev, pitch1, pitch2,
          cache, tangent):
    m = n_lines * zs.size
    force, stiff = np.empty(12), np.empty((12, 12))
    active, inside = np.empty(m, dtype=np.bool_), np.empty(m, dtype=np.bool_)
    delta, load, xi, z = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    for _ in range(n):
        if fresh:  # a new angle: the slices and the tangent computed again
            cache[-1, 0] = math.nan
        _mesh_kernel(angle, q, p, geo, xi_tab, k_tab, zs, dl, n_lines, dev, pitch1, pitch2,
                     cache, tangent, force, stiff, active, inside, delta, load, xi, z)
    return force, stiff


@njit
def _newton(n, s_lin, z0, xc, force, stiff):
    for _ in range(n):
        _newton_solve(s_lin, z0, xc, force, stiff)


def timed(calls: int, func, *args) -> float:
    """Best of 3 loops of ``calls`` calls [µs per call] (a first short loop compiles)."""
    func(2, *args)
    best = math.inf
    for _ in range(3):
        t0 = time.perf_counter()
        func(calls, *args)
        best = min(best, (time.perf_counter() - t0) / calls * 1e6)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=100, help="steps run before timing")
    parser.add_argument("--calls", type=int, default=20000, help="calls per timed loop")
    args = parser.parse_args()
    case = load_case("baguet2010_spur", {"bearings.*.model": "hybrid"})
    master = build_master(case, in_process=True)
    master.solve_static()
    master.exit_initialization()
    dt = time_step(case)
    st = master.structure.physics
    for _ in range(args.steps):
        master.step(st.t, dt)
    n = args.calls
    print(f"baguet2010_spur after {args.steps} steps; us per call, best of 3 loops of {n}")

    bearing = master.bearings.models[0]
    state, active = bearing._state.copy(), bearing._active.copy()
    ws, iws, trig = bearing._ws.copy(), bearing._iws.copy(), bearing._trig
    x, y, xd, yd = state[0]["q_prev"]
    res = np.empty((5, 2))
    us = timed(n, _kernel, state, x, y, xd, yd, active, ws, iws, trig, AXIAL_COEF, res)
    nt, nl = _kernel(1, state, x, y, xd, yd, active, ws, iws, trig, AXIAL_COEF, res)
    print(f"hybrid bearing 1 (n = {active.size}), warm call with the Jacobian ({nt} Newton "
          f"pass on t, {nl} active-set pass): {us:.2f}")
    g = np.empty(9)
    t, lam = float(state[0]["t"]), float(state[0]["lam"])
    rows = [("element integrals, with the Jacobian's weights",
             timed(n, _elements, ws, trig, x, y, True)),
            ("element integrals, force only", timed(n, _elements, ws, trig, x, y, False)),
            ("axial integrals G0 .. G2'' at t", timed(n, _axial, t, lam, AXIAL_COEF, g)),
            ("assembly of A and b", timed(n, _assemble, g, ws))]
    passes = _lcp_pass(1, ws, active, iws)
    rows.append((f"active-set method ({passes:.0f} pass: factors, solve, test)",
                 timed(n, _lcp_pass, ws, active, iws)))
    rows.append(("Thomas factors and solve of A_PP", timed(n, _factor_solve, ws, active, iws)))
    nr = _lcp.factor_solve(ws, active, iws[0], iws[1], ws[B], ws[A])
    out = np.empty(active.size)
    rows.append(("one more solve with the factors",
                 timed(n, _substitute, ws, active, iws, nr, out)))
    for label, value in rows:
        print(f"  {label:50s} {value:6.2f}")

    cond, g_const = st._dynamic(dt)
    unb = np.empty((st._unb_coef.shape[0], 2))
    unbalance_into(st._unb_coef, st.t + dt, unb)
    laws = master.laws
    step_args = (st._mc, cond.g_t, g_const, st.x, st.v, st.a, st._f_c, unb, st._unb_idx, laws.f0,
                 laws.kb, laws.cb, cond.s0, dt, st.ng)
    s_lin, z0, _ = prepare_step(*step_args, np.empty(0))
    memo = history_memo(st.x.size)
    prepare_step(*step_args, memo)  # the products kept, as after a first iteration
    mesh = st.meshes[0]
    print(f"structure step ({st._mc[0].shape[1]} x {st._mc[0].shape[0]} history product and its "
          f"{cond.g.shape[0]} x {cond.g.shape[1]} condensation, {st.nc} condensed "
          f"DOFs, {mesh.n_lines} x {mesh.n_slices} mesh slices)")
    angle = float(st.mesh_angles(st.input_angle(st.t))[0])
    q = np.ascontiguousarray(st.x[st._mesh_idx[0]])
    arrays = mesh.kernel_arrays()
    force, stiff = _mesh(1, True, angle, q, *arrays)
    xc = np.ascontiguousarray(st.x[:st.nc])
    rows = [("right-hand side and tangent (prepare_step)",
             timed(n, _prepare, *step_args, np.empty(0))),
            ("... at a later iteration of the step (memo)", timed(n, _prepare, *step_args, memo)),
            ("... its history product alone",
             timed(n, _history, st._mc, cond.g_t, st.x, st.v, st.a, dt)),
            ("one mesh evaluation, tangent assembled", timed(n, _mesh, True, angle, q, *arrays)),
            ("... at the angle and contact set of the last one",
             timed(n, _mesh, False, angle, q, *arrays)),
            ("one Newton solve of the condensed system",
             timed(n, _newton, s_lin, z0, xc, force, stiff))]
    for label, value in rows:
        print(f"  {label:50s} {value:6.2f}")

if __name__ == "__main__":
    main()
