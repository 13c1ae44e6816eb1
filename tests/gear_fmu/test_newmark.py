"""The structure's Newmark step (Eq. 11-16: :meth:`gear_fmu.structure.Structure.step` through
:mod:`gear_fmu.step.assembly`, :mod:`gear_fmu.step.contact_loop` and :mod:`gear_fmu.step.kernel`)
against exact solutions.

With a mesh whose springs never separate (:class:`BilateralMesh`) and affine bearing laws, the
paper's two-shaft structure is a linear time-invariant system ``M Xdd + C Xd + K X = F(t)``
whose loads are the torque, the bearings' F0 and the unbalance of Eq. (10), harmonic at both
shaft speeds. Its exact solution is written here from the reduced matrices: the periodic
response ``X_p(t)`` (one complex solve per frequency) plus the free response by the matrix
exponential of the first-order system. The step (gamma 1/2, beta 1/4) must follow it at order
2, conserve the energy of the undamped system exactly (the trapezoidal rule), and start at
order 2 only from the consistent acceleration. The compiled step (the distributed mesh
element) gives the Python loop's numbers bit for bit, so these checks, made through the loop
with the stand-in mesh, hold for the step of the runs.
"""

import math
import types

import numpy as np
import pytest
import scipy.linalg

from fmu_src import description
from fmu_src.case import load_case
from fmu_src.examples import paper_system
from gear_fmu.step.assembly import history_memo, history_products
from gear_fmu.step.condensation import NC
from gear_fmu.step.newmark import NewmarkConvergenceError
from gear_fmu.structure import Structure, StructureLoads, StructureState
from tests.helpers import T_IN, LineMesh

RNG = np.random.default_rng(1)
KB = np.broadcast_to(1e8 * np.eye(2), (4, 2, 2)) + 2e7 * RNG.standard_normal((4, 2, 2))
CB = np.broadcast_to(1e5 * np.eye(2), (4, 2, 2)).copy()
F0 = 100.0 * RNG.standard_normal((4, 2))
UNBALANCE = (0.6e-3, 0.6e-3)  # m


class BilateralMesh(LineMesh):
    """:class:`tests.helpers.LineMesh` whose springs never separate: a constant stiffness, so
    that the structure is linear."""

    def evaluate(self, pinion_angle, q12):
        delta = self.v @ q12 - self.e
        load = self.kdl * delta
        return types.SimpleNamespace(
            force=-(self.v.T @ load), stiffness=self.kdl * self.v.T @ self.v, delta=delta,
            load=load, active=np.ones(delta.size, dtype=bool), total_load=float(load.sum()),
            transmission_error=0.0)


def linear_structure(speed, laws=(F0, KB, CB), unbalance=UNBALANCE, **kw) -> Structure:
    """The paper's structure with :class:`BilateralMesh` at its static solution."""
    st = Structure(paper_system(), BilateralMesh(), StructureLoads(T_IN, speed, unbalance),
                   tol=1e-12, **kw)
    st.static(*laws)
    return st


def matrices(st, kb, cb):
    """Reduced M, C and K of the linear structure with the bearings' Kb and Cb and the mesh."""
    sys_ = st.system
    red = sys_.reduced_index
    m, c, k = (sys_.reduce(a).copy() for a in (sys_.mass, st.damping_full, sys_.stiffness))
    gear, brg = red[sys_.gear_dofs], red[sys_.bearing_dofs]
    k[np.ix_(gear, gear)] += st.mesh.evaluate(0.0, np.zeros(12)).stiffness
    for j in range(4):
        k[np.ix_(brg[j], brg[j])] += kb[j]
        c[np.ix_(brg[j], brg[j])] += cb[j]
    return m, c, k


def unbalance_phasors(st) -> list:
    """Eq. (10) as ``sum_k Re(P_k exp(i w_k t))``: ``[(w_k, P_k)]`` on the reduced DOFs (the
    pinion's force turns with it, the gear's against it at w1 z1 / z2)."""
    sys_ = st.system
    gear = sys_.reduced_index[sys_.gear_dofs]
    w1 = st.loads.input_speed
    w2 = w1 * sys_.teeth[0] / sys_.teeth[1]
    a1, a2 = (m * e * w**2 for m, e, w in zip(sys_.shaft_masses, st.loads.unbalance, (w1, w2),
                                               strict=True))
    p1, p2 = np.zeros(sys_.free.size, complex), np.zeros(sys_.free.size, complex)
    p1[gear[0]], p1[gear[1]] = a1, -1j * a1  # a1 (cos w1 t, sin w1 t)
    p2[gear[6]], p2[gear[7]] = a2, 1j * a2  # a2 (cos w2 t, -sin w2 t)
    return [(w1, p1), (w2, p2)]


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
    exact tangent, Eq. 13-16)."""
    speed = 2000.0
    exact = ExactSolution(linear_structure(speed))
    period = 2 * math.pi / speed
    steps, errors = [16, 32, 64, 128, 256], []
    for n in steps:
        st = linear_structure(speed)
        x0, v0, a0 = internal(st, *exact.periodic(0.0))
        st.set_state(StructureState(0.0, 0, x0, v0, a0, st.active, st.mesh_state))
        dt = period / n
        solves = {st.step(dt, F0, KB, CB).iterations for _ in range(n)}
        assert solves == {1}
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
    n_dof = paper_system().n_dof
    st = linear_structure(325.0, (F0, kb, cb), unbalance=(0.0, 0.0),
                          damping=np.zeros((n_dof, n_dof)))
    m, c, k = matrices(st, kb, cb)
    assert not c.any()
    x_static = st.system.reduce(st.full_vector("x"))
    (v0,) = internal(st, 1e-3 * np.random.default_rng(5).standard_normal(x_static.size))
    st.set_state(StructureState(0.0, 0, st.x, v0, np.zeros_like(v0), st.active, st.mesh_state))

    def energies():
        x = st.system.reduce(st.full_vector("x")) - x_static
        v = st.system.reduce(st.full_vector("v"))
        return 0.5 * v @ m @ v, 0.5 * x @ k @ x

    e0 = sum(energies())
    drift, potential = 0.0, 0.0
    for _ in range(2000):
        st.step(st.mesh_period / 32, F0, kb, cb)
        kinetic, pot = energies()
        drift = max(drift, abs((kinetic + pot) / e0 - 1.0))
        potential = max(potential, pot / e0)
    print(f"\nundamped structure, 2000 steps: energy kept to {drift:.1e}")
    assert potential > 0.3  # the energy moves between kinetic and potential: not trivial
    assert drift < 1e-9


def test_the_step_is_order_2_from_the_consistent_start_only():
    """From the static solution at rest, 10 ms of the unbalance's transient at 50 ... 400 steps
    against the exact solution (journal displacements): order 2 when the start acceleration is
    ``M^-1 F_unb(0)`` (``consistent_start``; measured 1.99), order 1 from ``Xdd_0 = 0`` (the
    wrong start acceleration is carried along by Eq. 12; measured 1.03)."""
    t_end, steps = 0.01, [50, 100, 200, 400]
    exact = ExactSolution(linear_structure(325.0)).from_rest(t_end)
    sys_ = paper_system()
    journals = sys_.reduced_index[sys_.bearing_dofs].ravel()
    orders = {}
    for consistent in (True, False):
        errors = []
        for n in steps:
            st = linear_structure(325.0, consistent_start=consistent)
            for _ in range(n):
                st.step(t_end / n, F0, KB, CB)
            x = st.system.reduce(st.full_vector("x"))
            errors.append(np.abs(x - exact)[journals].max())
        orders[consistent] = observed_order(steps, errors)
    print(f"\nstructure step from rest: order {orders[True]:.3f} from the consistent start, "
          f"{orders[False]:.3f} from Xdd_0 = 0")
    assert abs(orders[True] - 2.0) < 0.05
    assert orders[False] < 1.5


def test_the_compiled_step_equals_the_python_loop_bit_for_bit():
    """The paper's spur case (distributed mesh element, contact located) over 96 steps with
    anisotropic, cross-coupled laws: the compiled step (:func:`gear_fmu.step.kernel.advance`)
    and the Python loop it mirrors (taken when the structure's timers are on) give the same
    states, contact sets, mesh forces and tangents and residual histories to the last bit (the
    compiled step keeps the mesh tangent of its previous Newton pass when the contact set is
    the same; the loop assembles it at every pass)."""
    case = load_case("baguet2010_spur")
    rng = np.random.default_rng(1)
    kb = np.broadcast_to(2e8 * np.eye(2), (4, 2, 2)) + 3e7 * rng.standard_normal((4, 2, 2))
    cb = np.broadcast_to(2e4 * np.eye(2), (4, 2, 2)) + 2e3 * rng.standard_normal((4, 2, 2))
    f0 = 300.0 * rng.standard_normal((4, 2))
    dt = description.time_step(case)
    runs = []
    for timing in (None, {"mesh": 0.0, "assembly": 0.0, "solve": 0.0}):
        st = description.structure(case)
        st.static(f0, kb, cb)
        st.timing = timing
        history, changes, tangents = [], 0, []
        for _ in range(96):
            before = st.active
            history.append(st.step(dt, f0, kb, cb).residuals)
            changes += not np.array_equal(st.active, before)
            tangents.append(st.mesh_state.stiffness.copy())
        runs.append((st.x, st.v, st.a, st.active, st.mesh_state.force, np.array(tangents),
                     history, changes))
    compiled, loop = runs
    assert timing["mesh"] > 0.0  # the second run took the Python loop (its timers ran)
    assert compiled[7] >= 4  # the contact set changes (contact lines enter and leave)
    for a, b in zip(compiled[:6], loop[:6], strict=True):
        np.testing.assert_array_equal(a, b)
    assert compiled[6:] == loop[6:]


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
    for name in ("x", "v", "a", "active"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    np.testing.assert_array_equal(a.mesh_state.force, b.mesh_state.force)


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
        return [p.copy() for p in history_products(st._mc, cond.g, x, v, a, h, NC, memo)]

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


@pytest.mark.parametrize("mesh", ["stand-in", "mesh element"])
def test_non_convergence_names_the_step_the_time_and_the_residual(mesh):
    """Newton allowed no solve: the error names the step, its time and the residual history,
    from the Python loop and from the compiled step alike."""
    if mesh == "stand-in":
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
