"""The structure's Newmark step (Eq. 11-16: :meth:`gear_fmu.structure.Structure.step` through
:mod:`gear_fmu.step.assembly`, :mod:`gear_fmu.step.contact_loop` and :mod:`gear_fmu.step.kernel`)
against exact solutions.

The paper's two-shaft structure with its mesh element held at one angle (every slice on the
path of contact stays closed under the torque: a constant stiffness) and affine bearing laws
is a linear time-invariant system ``M Xdd + C Xd + K X = F(t)`` whose loads are the torque,
the bearings' F0 and the unbalances of Eq. (10), harmonic at both shaft speeds. Its exact
solution is written here from the reduced matrices: the periodic response ``X_p(t)`` (one
complex solve per frequency) plus the free response by the matrix exponential of the
first-order system. The step (gamma 1/2, beta 1/4) must follow it at order 2, conserve the
energy of the undamped system exactly (the trapezoidal rule), and start at order 2 only from
the consistent acceleration. These run the one compiled step of every run (the structure takes
mesh elements only; the Python contact loop and its stand-in meshes are gone); a step alone
(an FMU's) and the planned steps of the in-process master's compiled loop give the same bits.
"""

import math

import numpy as np
import pytest
import scipy.linalg

from fmu_src import description
from fmu_src.case import load_case
from fmu_src.examples import paper_case
from gear_fmu.dofs import U, V, dof
from gear_fmu.mesh.train import mesh_elements
from gear_fmu.modal.modes import mesh_dofs
from gear_fmu.step.assembly import (
    column_nonzeros,
    history_memo,
    history_products,
    matvec_t,
    matvec_t_sparse,
)
from gear_fmu.step.contact_loop import CONVERGED
from gear_fmu.step.events import step_times
from gear_fmu.step.kernel import advance_pieces, keep_evaluation
from gear_fmu.step.newmark import NewmarkConvergenceError
from gear_fmu.structure import Structure, StructureLoads, StructureState
from tests.helpers import T_IN

RNG = np.random.default_rng(1)
KB = np.broadcast_to(1e8 * np.eye(2), (4, 2, 2)) + 2e7 * RNG.standard_normal((4, 2, 2))
CB = np.broadcast_to(1e5 * np.eye(2), (4, 2, 2)).copy()
F0 = 100.0 * RNG.standard_normal((4, 2))
#: the pinion angle the mesh is held at [rad]: in the single-pair zone of a mesh period (a
#: two-pair angle, 0.3 of the period, makes the mesh mode stiffer: from rest, 50 steps of
#: 0.2 ms are then not yet asymptotic, local order 3.1 from 50 to 100 steps)
FROZEN = 0.85 * 2 * math.pi / 26


def linear_structure(speed, laws=(F0, KB, CB), torque=T_IN, overrides=None,
                     **kw) -> Structure:
    """The paper's structure (its unbalances, 0.6 mm on both shafts, unless ``overrides``
    say otherwise) with its mesh element held at the pinion angle FROZEN whatever the shafts'
    angles, at its static solution: every slice on the path of contact in contact (checked),
    so the mesh is a constant stiffness as long as none opens (checked by the tests)."""
    sys_ = description.gear_shaft_system(paper_case(0.0, **(overrides or {})))
    st = Structure(sys_, mesh_elements(sys_.layout), StructureLoads(torque, speed), tol=1e-12,
                   **kw)
    st.mesh_angles = lambda input_angle: np.array([FROZEN])  # the mesh held at one angle
    st.static(*laws)
    assert all_closed(st)
    return st


def all_closed(st) -> bool:
    """Every slice on the path of contact in contact (the mesh's stiffness is the constant
    one of the linear system)."""
    (ms,) = st.mesh_states
    return bool(np.array_equal(ms.active, ms.inside))


def matrices(st, kb, cb):
    """Reduced M, C and K of the linear structure with the bearings' Kb and Cb and the mesh."""
    sys_ = st.system
    red = sys_.reduced_index
    m, c, k = (sys_.reduce(a).copy() for a in (sys_.mass, st.damping_full, sys_.stiffness))
    gear, brg = red[mesh_dofs(sys_, 0)], red[sys_.bearing_dofs]
    k[np.ix_(gear, gear)] += st.mesh_states[0].stiffness  # all closed: the constant stiffness
    for j in range(4):
        k[np.ix_(brg[j], brg[j])] += kb[j]
        c[np.ix_(brg[j], brg[j])] += cb[j]
    return m, c, k


def unbalance_phasors(st) -> list:
    """Eq. (10) as ``sum_k Re(P_k exp(i w_k t))``: ``[(w_k, P_k)]`` on the reduced DOFs. Each
    unbalanced gear's force ``M e w^2 (cos(w t + phase), sin(w t + phase))`` turns with its
    shaft's signed speed w: the pinion's at omega about +z, the gear's at omega z1 / z2 about
    -z; M the mass of its shaft with the gear (the paper's case)."""
    sys_ = st.system
    lay = sys_.layout
    red = sys_.reduced_index
    w1 = st.loads.input_speed
    z1, z2 = (g.teeth for g in lay.gears)
    out = []
    for gear, node, w in zip(lay.gears, sys_.gear_nodes, (w1, -w1 * z1 / z2), strict=True):
        if gear.unbalance == 0.0:
            continue
        assert gear.unbalance_mass == "shaft"
        amplitude = lay.carried_mass(gear.shaft) * gear.unbalance * w**2
        p = np.zeros(sys_.free.size, complex)
        p[red[dof(node, U)]] = amplitude * np.exp(1j * gear.unbalance_phase)  # cos(w t + ph.)
        p[red[dof(node, V)]] = -1j * p[red[dof(node, U)]]  # sin(w t + phase)
        out.append((w, p))
    return out


class ExactSolution:
    """The exact trajectory of the linear structure ``st`` (reduced DOFs) from its static
    solution: ``periodic(t)`` (X, Xd, Xdd) and, from a start at rest, ``from_rest(t)`` (X)."""

    def __init__(self, st, kb=KB, cb=CB):
        sys_ = st.system
        self.m, self.c, self.k = matrices(st, kb, cb)
        self.static = sys_.reduce(st.full_vector("x"))
        self.modes = [(w, np.linalg.solve(self.k - w * w * self.m + 1j * w * self.c, p))
                      for w, p in unbalance_phasors(st)]

    def periodic(self, t):
        terms = [(w, x * np.exp(1j * w * t)) for w, x in self.modes]
        return (self.static + sum(z.real for _, z in terms),
                sum((1j * w * z).real for w, z in terms),
                sum((-w * w * z).real for w, z in terms))

    def from_rest(self, t):
        n = self.static.size
        minv = np.linalg.inv(self.m)
        a = np.block([[np.zeros((n, n)), np.eye(n)], [-minv @ self.k, -minv @ self.c]])
        x_p, v_p, _ = self.periodic(0.0)
        free = scipy.linalg.expm(a * t) @ np.concatenate([self.static - x_p, -v_p])
        return self.periodic(t)[0] + free[:n]


def internal(st, *vectors):
    """Reduced vectors in the structure's internal order (found through its public API)."""
    saved = st.get_state()
    st.x = np.arange(st.x.size, dtype=float)
    order = st.system.reduce(st.full_vector("x")).astype(int)
    st.set_state(saved)
    out = []
    for v in vectors:
        w = np.empty_like(v)
        w[order] = v
        out.append(w)
    return out


def observed_order(steps, errors) -> float:
    """Slope of log(error) against log(1 / steps)."""
    return float(np.polyfit(np.log(1.0 / np.asarray(steps, float)), np.log(errors), 1)[0])


def test_the_step_follows_the_exact_forced_response_at_order_2():
    """Started on the periodic response to the unbalance (2000 rad/s: the structure's inertia
    matters), one period of it at 16 ... 256 steps: the error against the exact response falls
    as dt^2 (measured 2.00), and each step takes one Newton solve (a linear problem with its
    exact tangent, Eq. 13-16), the mesh staying closed."""
    speed = 2000.0
    exact = ExactSolution(linear_structure(speed))
    period = 2 * math.pi / speed
    steps, errors = [16, 32, 64, 128, 256], []
    for n in steps:
        st = linear_structure(speed)
        x0, v0, a0 = internal(st, *exact.periodic(0.0))
        st.set_state(StructureState.of(0.0, 0, x0, v0, a0, st.mesh_states))
        dt = period / n
        solves, closed = set(), True
        for _ in range(n):
            solves.add(st.step(dt, F0, KB, CB).iterations)
            closed &= all_closed(st)
        assert solves == {1} and closed
        x = st.system.reduce(st.full_vector("x"))
        errors.append(np.abs(x - exact.periodic(n * dt)[0]).max())
    order = observed_order(steps, errors)
    amplitude = np.abs(exact.periodic(0.0)[0] - exact.static).max()
    print(f"\nstructure step vs exact forced response: errors "
          f"{', '.join(f'{e:.2e}' for e in errors)} m (amplitude {amplitude:.2e}), observed "
          f"order {order:.3f}")
    assert abs(order - 2.0) < 0.02
    assert errors[0] < 1e-2 * amplitude


def test_the_step_conserves_the_energy_of_the_undamped_structure():
    """No damping (C = 0, Cb = 0, symmetric Kb), no unbalance: from the static solution with
    random velocities on every DOF (modes far above 1 / dt included), 2000 steps keep
    ``Xd' M Xd / 2 + (X - X0)' K (X - X0) / 2`` to 1e-9 (measured 4.3e-11): the trapezoidal rule
    conserves it exactly for any dt; a scheme with numerical damping, or a wrong tangent, does
    not."""
    kb = 0.5 * (KB + KB.transpose(0, 2, 1))
    cb = np.zeros((4, 2, 2))
    n_dof = description.gear_shaft_system(paper_case()).n_dof
    st = linear_structure(325.0, (F0, kb, cb), overrides={"gears.*.unbalance": 0.0},
                          damping=np.zeros((n_dof, n_dof)))
    m, c, k = matrices(st, kb, cb)
    assert not c.any()
    x_static = st.system.reduce(st.full_vector("x"))
    (v0,) = internal(st, 1e-3 * np.random.default_rng(5).standard_normal(x_static.size))
    st.set_state(StructureState.of(0.0, 0, st.x, v0, np.zeros_like(v0), st.mesh_states))

    def energies():
        x = st.system.reduce(st.full_vector("x")) - x_static
        v = st.system.reduce(st.full_vector("v"))
        return 0.5 * v @ m @ v, 0.5 * x @ k @ x

    e0 = sum(energies())
    drift, potential = 0.0, 0.0
    for _ in range(2000):
        st.step(st.mesh_period / 32, F0, kb, cb)
        assert all_closed(st)
        kinetic, pot = energies()
        drift = max(drift, abs((kinetic + pot) / e0 - 1.0))
        potential = max(potential, pot / e0)
    print(f"\nundamped structure, 2000 steps: energy kept to {drift:.1e}")
    assert potential > 0.3  # the energy moves between kinetic and potential: not trivial
    assert drift < 1e-9


def test_the_step_is_order_2_from_the_consistent_start_only():
    """From the static solution at rest, 10 ms of the unbalance's transient at 50 ... 400 steps
    against the exact solution (journal displacements): order 2 when the start acceleration is
    ``M^-1 F_unb(0)`` (``consistent_start``; measured 2.03, local orders 2.07, 2.02, 2.00),
    order 1 from ``Xdd_0 = 0`` (the wrong start acceleration is carried along by Eq. 12;
    measured 1.03)."""
    t_end, steps = 0.01, [50, 100, 200, 400]
    exact = ExactSolution(linear_structure(325.0)).from_rest(t_end)
    sys_ = description.gear_shaft_system(paper_case())
    journals = sys_.reduced_index[sys_.bearing_dofs].ravel()
    orders = {}
    for consistent in (True, False):
        errors = []
        for n in steps:
            st = linear_structure(325.0, consistent_start=consistent)
            for _ in range(n):
                st.step(t_end / n, F0, KB, CB)
                assert all_closed(st)
            x = st.system.reduce(st.full_vector("x"))
            errors.append(np.abs(x - exact)[journals].max())
        orders[consistent] = observed_order(steps, errors)
    print(f"\nstructure step from rest: order {orders[True]:.3f} from the consistent start, "
          f"{orders[False]:.3f} from Xdd_0 = 0")
    assert abs(orders[True] - 2.0) < 0.05
    assert orders[False] < 1.5


def _planned_steps(st, dt, n, laws):
    """``n`` steps of dt as the in-process master's compiled loop takes them
    (:func:`orchestrator.coupling.step.coupled_steps` with the structure's plan, the laws fixed):
    :meth:`~gear_fmu.structure.Structure.steps_plan`, per step the kernel's
    :func:`~gear_fmu.step.kernel.advance_pieces` and the accepted state kept, then
    :meth:`~gear_fmu.structure.Structure.end_steps`. Returns per step (residual history of
    its last sub-step, mesh loads)."""
    f0, kb, cb = laws
    out = []
    while len(out) < n:
        plan = st.steps_plan(dt, n - len(out))
        counts, slots, mc, g_k, gc_k, s0_k, w_k, table, angles, after, errs, errs_a = plan.head
        x, v, a = plan.state
        unb_coef, unb_idx, f_c, has_err, meshes, f_scale, tol, max_iter, m_inv_g, memo = \
            plan.tail
        fc, kc, totals, lengths, residuals, x1, v1, a1 = plan.work
        for i in range(len(plan.ends)):
            row = i if has_err else 0
            status, _, k = advance_pieces(
                counts[i], slots[i], mc, g_k, gc_k, s0_k, w_k, table[i], angles[i], after[i],
                errs[row], errs_a[row], x, v, a, f_c, unb_coef, unb_idx, f0, kb, cb, has_err,
                meshes, fc, kc, totals, lengths, f_scale, tol, max_iter, m_inv_g, residuals,
                x1, v1, a1, memo)
            assert status == CONVERGED
            x[:], v[:], a[:] = x1, v1, a1
            keep_evaluation(meshes)
            out.append((residuals[:k + 1].tolist(), totals.copy()))
        st.end_steps(plan, len(plan.ends), totals, lengths)
    return out


def test_a_step_alone_equals_the_planned_steps_bit_for_bit():
    """The paper's spur case (mesh element, contact located) over 96 steps with anisotropic,
    cross-coupled laws: a step alone (:meth:`~gear_fmu.structure.Structure.step`, an FMU's)
    and the planned steps of the in-process master's compiled loop give the same states,
    contact sets, mesh forces and tangents and residual histories to the last bit, the
    contact set changing along the way (contact lines enter and leave). (The Python contact
    loop this once compared with is gone: the compiled step is the only one.)"""
    case = load_case("baguet2010_spur")
    rng = np.random.default_rng(1)
    kb = np.broadcast_to(2e8 * np.eye(2), (4, 2, 2)) + 3e7 * rng.standard_normal((4, 2, 2))
    cb = np.broadcast_to(2e4 * np.eye(2), (4, 2, 2)) + 2e3 * rng.standard_normal((4, 2, 2))
    f0 = 300.0 * rng.standard_normal((4, 2))
    dt = description.time_step(case)
    alone, planned = (description.structure(case) for _ in range(2))
    for st in (alone, planned):
        st.static(f0, kb, cb)
    steps, changes = [], 0
    for _ in range(96):
        before = alone.mesh_states[0].active
        info = alone.step(dt, f0, kb, cb)
        steps.append((info.residuals, alone.mesh_forces()))
        changes += not np.array_equal(alone.mesh_states[0].active, before)
    assert changes >= 4
    other = _planned_steps(planned, dt, 96, (f0, kb, cb))
    for (res_a, load_a), (res_p, load_p) in zip(steps, other, strict=True):
        assert res_a == res_p
        np.testing.assert_array_equal(load_a, load_p)
    _same_state(alone, planned)
    (ma,), (mp,) = alone.mesh_states, planned.mesh_states
    np.testing.assert_array_equal(ma.stiffness, mp.stiffness)
    assert (alone.t, alone.n_steps) == (planned.t, planned.n_steps)


def _reference_plan(st, dt, n):
    """Per step (its pieces' slot lengths, end times, angles before and after, error
    displacements before and after) as :meth:`~gear_fmu.structure.Structure._pieces` cuts the
    steps one by one from the structure's time, ``t + dt`` after ``t``
    (:func:`gear_fmu.step.events.train_pieces`)."""
    out, t = [], st.t
    for _ in range(n):
        pieces = st._pieces(dt, t)
        rows = []
        for h, te, before, aft in pieces:
            before, aft = np.asarray(before, dtype=float), np.asarray(aft, dtype=float)
            rows.append((h, te, before, aft, st._errors(before),
                         st._errors(np.where(np.isnan(aft), before, aft))))
        out.append(rows)
        t = pieces[-1][1]
    return out


@pytest.mark.parametrize("name, overrides, drift", [
    ("baguet2010_spur", {}, 0.0),
    ("baguet2010_helical", {}, 0.0),
    ("two_stage_reducer", {}, 0.0),
    ("baguet2010_spur", {"gears.pinion.runout": 5e-6, "gears.gear.runout_phase": 0.3}, 0.0),
    ("baguet2010_spur", {}, 3e-7),  # a step that does not recur with the mesh period
    ("baguet2010_spur", {"simulation.locate_contact": False}, 0.0),
])
def test_a_plan_of_many_steps_cuts_each_as_a_step_alone(name, overrides, drift):
    """:meth:`~gear_fmu.structure.Structure.steps_plan` fills the steps without a contact
    event at once (:func:`gear_fmu.step.events.quiet_steps`): over 600 steps (19 mesh
    periods) its sub-step lengths, slots, end times, angles and error displacements are the
    bits of the steps cut one by one (:func:`_reference_plan`), and so are those of a step
    alone (``_one_step``, looking ahead the same way), for one and two meshes, tooth
    errors, a step that drifts through the mesh period and no contact location; and most
    steps of one piece are found quiet (the test would not see the fast path otherwise)."""
    case = load_case(name, overrides)
    st = description.structure(case)
    st.static(np.zeros((st.nb, 2)), np.broadcast_to(2e8 * np.eye(2), (st.nb, 2, 2)).copy(),
              np.broadcast_to(2e4 * np.eye(2), (st.nb, 2, 2)).copy())
    dt = description.time_step(case) * (1.0 + drift)
    n = 600
    reference = _reference_plan(st, dt, n)
    plan = st.steps_plan(dt, n)
    counts, index, _, g_k, _, _, _, table, angles, after, errs, errs_a = plan.head
    assert len(plan.ends) == n
    single = 0
    for i, rows in enumerate(reference):
        assert counts[i] == len(rows), f"step {i}"
        assert plan.ends[i] == [te for _, te, _, _, _, _ in rows], f"step {i}"
        single += len(rows) == 1 and bool(np.isnan(rows[0][3]).all())
        for p, (h, te, before, aft, err, err_a) in enumerate(rows):
            assert (table[i, p, 0], table[i, p, 1]) == (h, te), f"step {i}, piece {p}"
            np.testing.assert_array_equal(angles[i, p], before, f"step {i}, piece {p}")
            np.testing.assert_array_equal(after[i, p], aft, f"step {i}, piece {p}")
            cond, _ = st._dynamic(h)
            np.testing.assert_array_equal(g_k[index[i, p]], cond.g_t)
            if st._has_err:
                np.testing.assert_array_equal(errs[i, p], err)
                np.testing.assert_array_equal(errs_a[i, p], err_a)
    assert st._has_err == ("gears.pinion.runout" in overrides)
    # a step alone (an FMU's), from the times the steps reach one after the other
    t = st.t
    for i, rows in enumerate(reference):
        n_p, index, table, angles, after, errs, errs_a, end = st._one_step(dt)
        assert n_p == len(rows) and end == rows[-1][1], f"step {i}"
        for p, (h, te, before, aft, err, err_a) in enumerate(rows):
            assert (table[p, 0], table[p, 1]) == (h, te), f"step {i}, piece {p}"
            np.testing.assert_array_equal(angles[p], before, f"step {i}, piece {p}")
            np.testing.assert_array_equal(after[p], aft, f"step {i}, piece {p}")
            if st._has_err:
                np.testing.assert_array_equal(errs[p], err)
                np.testing.assert_array_equal(errs_a[p], err_a)
        st.t = end
    st.t = t
    quiet = st._quiet_steps(step_times(st.t, dt, n))
    # (measured: 544 of the spur case's 563 steps of one piece, all of the helical case's 38
    # and of the two-stage reducer's 74: the widened search flags a few with an event at
    # their start, which the step before ended on)
    assert 0.9 * single <= quiet.sum() <= single


def _spur_structure(steps):
    """The paper's spur structure (mesh element) after its static solution and ``steps``
    steps with the module's laws; and its time step [s]."""
    case = load_case("baguet2010_spur")
    dt = description.time_step(case)
    st = description.structure(case)
    st.static(F0, KB, CB)
    for _ in range(steps):
        st.step(dt, F0, KB, CB)
    return st, dt


def _same_state(a, b):
    for name in ("x", "v", "a"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    for ma, mb in zip(a.mesh_states, b.mesh_states, strict=True):
        np.testing.assert_array_equal(ma.active, mb.active)
        np.testing.assert_array_equal(ma.force, mb.force)


def test_a_step_taken_again_with_other_laws_is_the_step_of_a_fresh_structure():
    """The master takes a step again from the same state at each iteration, with other
    bearing laws; the structure keeps the step's history products, which do not depend on
    them (:func:`gear_fmu.step.assembly.history_products`). Taken again, and taken from
    there on, the steps give what a structure that never took the first one gives, to the
    bit, and so does a step taken again after the damping matrix changed."""
    st, dt = _spur_structure(3)
    saved = st.get_state()
    st.step(dt, F0, KB, CB)  # the master's first iteration
    st.set_state(saved)
    laws = (1.5 * F0, 0.7 * KB, 1.3 * CB)
    st.step(dt, *laws)
    fresh, _ = _spur_structure(3)
    fresh.step(dt, *laws)
    _same_state(st, fresh)
    for _ in range(2):
        st.step(dt, *laws)
        fresh.step(dt, *laws)
    _same_state(st, fresh)
    # the damping changed between two iterations of one step (a run replaces it before its
    # first step): the products of the old C must not serve
    saved = st.get_state()
    st.step(dt, *laws)
    st.set_state(saved)
    damping = 1.2 * st._damping_full
    st.set_damping(damping)
    st.step(dt, *laws)
    fresh.set_damping(damping)
    fresh.step(dt, *laws)
    _same_state(st, fresh)


def test_the_history_memo_answers_only_inputs_of_the_same_bits():
    """The memo of the history products (:func:`gear_fmu.step.assembly.history_products`)
    serves a call only when dt, X, Xd and Xdd have the bits of the call that filled it: a
    relative change of 1e-9 in one entry of any of them, or of dt, gives the products of a
    call without the memo, and a zero of the other sign is another input."""
    st, dt = _spur_structure(2)
    cond, _ = st._dynamic(dt)
    n = st.x.size
    base = [st.x.copy(), st.v.copy(), st.a.copy(), dt]
    no_memo = np.empty(0)

    def products(inputs, memo):
        x, v, a, h = inputs
        return [p.copy() for p in history_products(st._mc, cond.g_t, x, v, a, h, st.nc, memo)]

    plain = products(base, no_memo)
    for which in range(4):
        other = [u.copy() if isinstance(u, np.ndarray) else u for u in base]
        if which == 3:
            other[3] = dt * (1.0 + 1e-9)
        else:
            other[which][7] *= 1.0 + 1e-9
        memo = history_memo(n)
        for _ in range(2):  # filled, then served from the memo
            for p, q in zip(products(base, memo), plain, strict=True):
                np.testing.assert_array_equal(p, q)
        changed = products(other, memo)
        expected = products(other, no_memo)
        assert not np.array_equal(expected[0], plain[0])  # the change reaches the products
        for p, q in zip(changed, expected, strict=True):
            np.testing.assert_array_equal(p, q)
    zero = [np.zeros(n), np.zeros(n), np.zeros(n), dt]
    memo = history_memo(n)
    products(zero, memo)
    zero[1][5] = -0.0
    products(zero, memo)
    assert math.copysign(1.0, memo[1 + n + 5]) == -1.0  # the memo took the new input


@pytest.mark.parametrize("mesh", ["held at one angle", "turning"])
def test_non_convergence_names_the_step_the_time_and_the_residual(mesh):
    """Newton allowed no solve: the error names the step, its time and the residual history,
    for the linear structure and the paper's case alike."""
    if mesh == "held at one angle":
        st = linear_structure(325.0)
    else:
        st = description.structure(load_case("baguet2010_spur"))
        st.static(F0, KB, CB)
    dt = st.mesh_period / 32
    for _ in range(6):
        st.step(dt, F0, KB, CB)
    st.max_iter, st.tol = 0, 1e-15
    with pytest.raises(NewmarkConvergenceError,
                       match=r"Newmark step 7 at t = 0\.000\d+ s did not converge: relative "
                             r"residual \S+ \(tol 1\.0e-15\) after 0 iterations"):
        st.step(dt, F0, KB, CB)


@pytest.mark.parametrize("k", [1, 3, 4, 7, 8, 13])
def test_the_steps_product_sums_in_the_order_of_its_rows(k):
    """``matvec_t`` takes four rows at a time but must add each entry's terms one by one in
    the order of j (its docstring): Python's own floats summed that way give the same bits,
    for row counts below, at and between multiples of four."""
    at = RNG.standard_normal((k, 5)) * np.logspace(0, 12, k)[:, None]
    x = RNG.standard_normal(k)
    expected = [0.0] * 5
    for j in range(k):
        for i in range(5):
            expected[i] = expected[i] + float(at[j, i]) * float(x[j])
    assert matvec_t(at, x).tolist() == expected


def test_the_sparse_product_has_the_bits_of_the_dense_one():
    """``matvec_t_sparse`` leaves out the zeros of M's half of [M C]^T: the paper case's
    [M C]^T with the nonzeros of its M (and a random sparse matrix with zeros of both signs
    stored, negative x) gives the bits of :func:`matvec_t`, whose order it keeps; the
    nonzeros listed are exactly the matrix's."""
    st, _ = _spur_structure(2)
    mc_t, indptr, indices = st._mc
    n = indptr.size - 1
    assert indices.size < 0.1 * n * n  # sparse: the point of it
    for j in range(n):
        assert indices[indptr[j]:indptr[j + 1]].tolist() == np.flatnonzero(mc_t[j]).tolist()
    for _ in range(5):
        x = RNG.standard_normal(2 * n) * np.logspace(-9, 3, 2 * n)
        assert matvec_t_sparse(mc_t, indptr, indices, x).tolist() == matvec_t(mc_t, x).tolist()
    m, k = 9, 23  # sparse rows, then dense rows not a multiple of four
    at = RNG.standard_normal((k, 11))
    at[:m][RNG.random((m, 11)) < 0.7] = 0.0
    at[:m][RNG.random((m, 11)) < 0.1] = -0.0
    x = -np.abs(RNG.standard_normal(k))
    ptr, idx = column_nonzeros(at[:m].T)
    assert matvec_t_sparse(at, ptr, idx, x).tolist() == matvec_t(at, x).tolist()
    ptr, idx = column_nonzeros(np.zeros((3, 2)))
    assert ptr.tolist() == [0, 0, 0] and idx.size == 0
