"""The gear-shaft Structure: statics, condensed Newmark step, rollback, master emulation.

The structure is the paper's train (Fig. 1, Tables 1-2) with its distributed mesh element
(:mod:`gear_fmu.mesh.element`): unilateral springs spread over the face width on the contact
lines, whose number changes with the angle (one or two tooth pairs), with an optional lead
slope that opens part of the face. The generic Newmark step of
:mod:`tests.gear_fmu.reference_newmark` on the full system (``tests.helpers
.monolithic_structure``: the same mesh elements, the loads written out) is the independent
reference of the condensed, compiled step.
"""

import math

import numpy as np
import pytest

from fmu_src import description
from fmu_src.examples import paper_case, paper_gear_pair
from gear_fmu.mesh.train import mesh_elements
from gear_fmu.modal.analyses import support_loads
from gear_fmu.step.newmark import NewmarkConvergenceError
from gear_fmu.structure import Structure, StructureLoads
from tests.gear_fmu.reference_newmark import newmark_step
from tests.helpers import OMEGA, T_IN, affine, monolithic_structure

PAIR = paper_gear_pair()
#: the paper's pair: operating pressure angle (x1 + x2 = 0: the standard 20 deg), base and
#: pitch radii
ALPHA = PAIR.operating_pressure_angle
RB1, RB2 = PAIR.base_radius
#: no unbalance (the structure's own loads only), and the paper's (0.6 mm on both shafts)
BALANCED = {"gears.*.unbalance": 0.0}


def iso(value, n=4):
    return np.broadcast_to(value * np.eye(2), (n, 2, 2)).copy()


def system(**overrides):
    """The paper's system (8 elements a shaft) with case overrides."""
    return description.gear_shaft_system(paper_case(0.0, **overrides))


def make(loads=None, overrides=BALANCED, **kw):
    """The paper's structure, its case with ``overrides`` (default: no unbalance)."""
    sys_ = system(**overrides)
    return Structure(sys_, mesh_elements(sys_.layout),
                     StructureLoads() if loads is None else loads, **kw)


def test_static_reactions_balance_the_mesh_force_and_are_symmetric():
    st = make(zeta=0.0)
    kb = iso(1e9)
    info = st.static(np.zeros((4, 2)), kb)
    assert info.residual < 1e-10
    reac = -np.einsum("bij,bj->bi", kb, st.journal_states()[:, :2])
    # the bearings carry no torque: the mesh load balances the input torque alone
    w = T_IN / RB1
    assert st.mesh_forces()[0] == pytest.approx(w, rel=1e-9)
    n = np.array([math.sin(ALPHA), math.cos(ALPHA)])
    np.testing.assert_allclose(reac[0] + reac[1], w * n, rtol=1e-9)  # pinion shaft
    np.testing.assert_allclose(reac[2] + reac[3], -w * n, rtol=1e-9)  # gear shaft
    np.testing.assert_allclose(reac[0], reac[1], rtol=1e-9)  # symmetric spur system
    np.testing.assert_allclose(reac[2], reac[3], rtol=1e-9)
    # resisting torque = reaction of the clamped output: T z2 / z1 about +z on the structure
    sys_ = st.system
    moment = (sys_.stiffness @ st.full_vector("x"))[sys_.output_dof]
    assert -moment == pytest.approx(-T_IN * RB2 / RB1, rel=1e-9)
    assert RB2 / RB1 == pytest.approx(157 / 26, rel=1e-14)
    # loads on stiff supports (first guess for the master)
    np.testing.assert_allclose(support_loads(st), -reac, rtol=1e-3)


def test_gravity_is_carried_by_the_bearings():
    """The mesh force is internal to the pair of shafts: the four reactions sum to the weight."""
    g = np.array([0.0, -9.81])
    st = make(loads=StructureLoads(gravity=tuple(g)), zeta=0.0)
    kb = iso(1e9)
    st.static(np.zeros((4, 2)), kb)
    reac = -np.einsum("bij,bj->bi", kb, st.journal_states()[:, :2])
    total_mass = st.system.shaft_masses.sum()
    np.testing.assert_allclose(reac.sum(axis=0), -total_mass * g, rtol=1e-9, atol=1e-9)
    # the pinion shaft's bearings carry its weight plus the mesh force
    n = np.array([math.sin(ALPHA), math.cos(ALPHA)])
    w_mesh = st.mesh_forces()[0]
    np.testing.assert_allclose(reac[0] + reac[1], w_mesh * n - st.system.shaft_masses[0] * g,
                               rtol=1e-9)


@pytest.mark.parametrize("gyroscopic", [False, True])
def test_condensed_step_equals_generic_newmark_on_the_full_system(gyroscopic):
    """Time-varying (one or two tooth pairs), partially open mesh (a lead slope of 40 um
    across the face), the paper's unbalance, anisotropic bearing laws; with the gyroscopic
    matrix, the unsymmetric tangent's LU condensation (at 10x the paper's speed, where it
    moves the run by more than the bound)."""
    loads = StructureLoads(T_IN, OMEGA * (10.0 if gyroscopic else 1.0))
    st = make(loads, overrides={"meshes.mesh.lead_slope": "40 um"}, gyroscopic=gyroscopic)
    rng = np.random.default_rng(1)
    kb = iso(1e8) + 2e7 * rng.standard_normal((4, 2, 2))
    cb = iso(1e5) + 2e4 * rng.standard_normal((4, 2, 2))
    f0 = 100.0 * rng.standard_normal((4, 2))
    st.static(f0, kb, cb)
    (ms,) = st.mesh_states
    assert 0 < np.count_nonzero(ms.active) < np.count_nonzero(ms.inside)  # partial contact
    m, c, k, force, nl_at = monolithic_structure(st, affine(f0, kb, cb))
    sys_ = st.system
    x = sys_.reduce(st.full_vector("x"))
    v = np.zeros_like(x)
    a = np.zeros_like(x)
    act = ms.active
    dt = st.mesh_period / 32
    changes = 0
    for i in range(96):
        info = st.step(dt, f0, kb, cb)
        x, v, a, ref = newmark_step(m, c, k, dt, (i + 1) * dt, x, v, a, force, nl_at((i + 1) * dt),
                                    active0=act, tol=1e-9)
        changes += not np.array_equal(ref.active, act)
        act = ref.active
        np.testing.assert_array_equal(st.mesh_states[0].active, act)
        assert info.residual <= st.tol
        np.testing.assert_allclose(sys_.reduce(st.full_vector("x")), x, rtol=0,
                                   atol=1e-8 * np.abs(x).max())
        np.testing.assert_allclose(sys_.reduce(st.full_vector("v")), v, rtol=0,
                                   atol=1e-7 * np.abs(v).max())
    assert changes > 0  # the contact set did change during the run


def test_state_rollback_is_exact():
    st = make(loads=StructureLoads(T_IN, OMEGA), overrides={"gears.gear.unbalance": "0.3 mm"})
    kb, cb, f0 = iso(1e8), iso(1e5), np.zeros((4, 2))
    st.static(f0, kb, cb)
    dt = st.mesh_period / 32
    for _ in range(5):
        st.step(dt, f0, kb, cb)
    saved = st.get_state()
    st.step(dt, f0, kb, cb)
    first = (st.x.copy(), st.v.copy(), st.a.copy(), st.t)
    st.set_state(saved)
    st.step(dt, f0 + 500.0, 2 * kb, cb)  # a different law moves the structure elsewhere
    assert np.abs(st.x - first[0]).max() > 1e-9
    st.set_state(saved)
    st.step(dt, f0, kb, cb)
    for got, ref in zip((st.x, st.v, st.a, st.t), first, strict=True):
        np.testing.assert_array_equal(got, ref)


def test_a_new_damping_acts_at_the_next_step_as_if_built_with_it():
    """The compiled step holds the structure's arrays between steps
    (:meth:`~gear_fmu.structure.Structure._held_arrays`): a damping set between two steps
    (new [M C] and condensations) gives the bits of a structure that had it from the start,
    stepping from the same state, and not those of the old damping."""
    kb, cb, f0 = iso(1e8), iso(1e5), np.zeros((4, 2))
    st = make(loads=StructureLoads(T_IN, OMEGA))
    st.static(f0, kb, cb)
    dt = st.mesh_period / 32
    for _ in range(3):
        st.step(dt, f0, kb, cb)
    saved = st.get_state()
    c2 = 3.0 * st._damping_full
    st.step(dt, f0, kb, cb)
    old = st.x.copy()
    st.set_state(saved)
    st.set_damping(c2)
    st.step(dt, f0, kb, cb)
    fresh = make(loads=StructureLoads(T_IN, OMEGA))
    fresh.set_damping(c2)
    fresh.set_state(saved)
    fresh.step(dt, f0, kb, cb)
    np.testing.assert_array_equal(st.x, fresh.x)
    np.testing.assert_array_equal(st.a, fresh.a)
    assert np.abs(st.x - old).max() > 1e-12


# ---------------------------------------------------------------- master emulation
K1, K3, CB = 1e8, 4e17, 1e5  # cubic bearing: F = -(K1 + K3 |X|^2) X - CB Xdot


def cubic_bearing(j, x, v):
    r2 = x @ x
    f = -(K1 + K3 * r2) * x - CB * v
    kb = (K1 + K3 * r2) * np.eye(2) + 2 * K3 * np.outer(x, x)  # -dF/dX, exact
    return f, kb, CB * np.eye(2)


def linearise(states):
    f0 = np.zeros((4, 2))
    kb = np.zeros((4, 2, 2))
    cb = np.zeros((4, 2, 2))
    for j in range(4):
        f, kb[j], cb[j] = cubic_bearing(j, states[j, :2], states[j, 2:])
        f0[j] = f + kb[j] @ states[j, :2] + cb[j] @ states[j, 2:]
    return f0, kb, cb


def mismatch(states, laws):
    f0, kb, cb = laws
    err = 0.0
    ref = 0.0
    for j in range(4):
        f = cubic_bearing(j, states[j, :2], states[j, 2:])[0]
        fa = f0[j] - kb[j] @ states[j, :2] - cb[j] @ states[j, 2:]
        err = max(err, np.abs(f - fa).max())
        ref = max(ref, np.abs(f).max())
    return err / ref


def test_master_emulation_converges_to_the_monolithic_newton_solution():
    """Save -> affine law at last iterate -> step -> re-linearise -> restore, against Newton with
    the cubic bearings inside the residual (Eq. 14, 16)."""
    st = make(loads=StructureLoads(T_IN, OMEGA), overrides={})  # the paper's unbalance
    # static: iterate laws (what the master does for X0)
    states = np.zeros((4, 4))
    for _ in range(30):
        laws = linearise(states)
        st.static(*laws)
        states = st.journal_states().copy()
        if mismatch(states, laws) < 1e-12:
            break
    else:
        raise AssertionError("static coupling did not converge")
    assert np.abs(states[:, :2]).max() > 5e-6  # the cubic term matters (K3 r^2 ~ K1 at 16 um)
    m, c, k, force, nl_at = monolithic_structure(st, cubic_bearing)
    sys_ = st.system
    x = sys_.reduce(st.full_vector("x"))
    v, a = np.zeros_like(x), np.zeros_like(x)
    act = st.mesh_states[0].active
    dt = st.mesh_period / 32
    iters = []
    for i in range(64):
        saved = st.get_state()
        it = 0
        while it < 30:
            it += 1
            st.step(dt, *laws)
            states = st.journal_states().copy()
            mis = mismatch(states, laws)
            laws = linearise(states)
            if mis < 1e-11:
                break
            st.set_state(saved)
        else:
            raise AssertionError(f"coupling did not converge at step {i}")
        iters.append(it)
        x, v, a, ref = newmark_step(m, c, k, dt, (i + 1) * dt, x, v, a, force, nl_at((i + 1) * dt),
                                    active0=act, tol=1e-10)
        act = ref.active
        np.testing.assert_allclose(sys_.reduce(st.full_vector("x")), x, rtol=0,
                                   atol=1e-7 * np.abs(x).max())
    print(f"\nmaster emulation: mean {np.mean(iters):.2f} coupling iterations per step")
    assert 1 < np.mean(iters) < 6


def test_no_contact_is_a_clear_error():
    st = make(loads=StructureLoads(torque=-220.0), zeta=0.0)
    with pytest.raises(NewmarkConvergenceError, match="torque sign"):
        st.static(np.zeros((4, 2)), iso(1e9))


def test_bad_laws_are_rejected():
    st = make(zeta=0.0)
    st.static(np.zeros((4, 2)), iso(1e9))
    with pytest.raises(ValueError, match="shapes"):
        st.step(1e-5, np.zeros((3, 2)), iso(1e8), iso(1e5))
    bad = iso(1e8)
    bad[0, 0, 0] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        st.step(1e-5, np.zeros((4, 2)), bad, iso(1e5))
    with pytest.raises(ValueError, match="dt"):
        st.step(-1.0, np.zeros((4, 2)), iso(1e8), iso(1e5))


def test_the_compiled_force_norm_is_numpys():
    """The residual scale inside the compiled step (``gear_fmu.step.kernel.sum_squares``) is
    ``np.sum(f0 * f0)`` bit for bit (numpy's pairwise order), over 20,000 draws spanning
    ten decades: the steps accept exactly where the Python loop does."""
    from gear_fmu.step.kernel import sum_squares

    rng = np.random.default_rng(3)
    for _ in range(20000):
        f0 = rng.normal(size=(4, 2)) * 10.0 ** rng.integers(-4, 6, size=(4, 2))
        assert sum_squares(f0) == np.sum(f0 * f0)


@pytest.mark.parametrize("name", ["baguet2010_spur", "baguet2010_spur_motor"])
def test_a_new_torque_acts_as_if_built_with_it(name):
    """``set_torque`` on a structure built for the case's torque, after it has stepped (its
    step factorisation cached), gives the bits of a structure built with the new torque from
    the start (the same mesh element): the static solution balances the new torque through
    the mesh (W = T / r_b1), and the steps that follow are the same (without the factorisation
    cached for the old torque updated, they are not). Output end clamped, and a motor behind a
    coupling."""
    from dataclasses import replace

    from fmu_src import description as d
    from fmu_src.case import load_case

    case = load_case(name)
    new = 1.5 * case["drive.torque"]
    (pair,) = d.gear_pairs(case)

    def build(torque):
        return Structure(d.gear_shaft_system(case), d.mesh_elements_of(case),
                         replace(d.structure_loads(case), torque=torque), zeta=d.damping(case))

    kb, cb = iso(2e8), iso(1e4)
    f0 = np.zeros((4, 2))
    dt = d.time_step(case)
    built, changed = build(new), build(case["drive.torque"])
    changed.static(f0, kb)
    changed.set_damping_reference(kb)
    changed.step(dt, f0, kb, cb)  # fills the cache of the step's factorisation
    changed.t, changed.n_steps = 0.0, 0
    changed.set_torque(new)
    changed.static(f0, kb)  # the damping and the step's factorisation kept
    built.static(f0, kb)
    built.set_damping_reference(kb)
    assert changed.mesh_forces()[0] == pytest.approx(new / pair.base_radius[0], rel=1e-6)
    assert np.array_equal(changed.x, built.x)
    for _ in range(4):
        built.step(dt, f0, kb, cb)
        changed.step(dt, f0, kb, cb)
        assert np.array_equal(changed.x, built.x) and np.array_equal(changed.a, built.a)
    with pytest.raises(ValueError, match="torque"):
        changed.set_torque(math.nan)


def test_a_run_down_takes_the_gyroscopic_matrix_at_each_steps_speed():
    """A run-down from 10x the paper's speed by 3 % over 96 steps with the gyroscopic matrix
    (docs/equations.md "Run-ups"): the condensed step rebuilds its tangent at each step's end
    speed; the generic Newmark step on the full system, given ``C + G(Omega(t1))`` and the
    ramp's inertia load ``-M u_rb dOmega/dt`` written out here, is its reference (bounds of
    the constant-speed test above). The same reference with G frozen at the start's speed
    is more than 10x the bound away: the test sees a speed the matrix does not follow."""
    from gear_fmu.speed_profile import SpeedProfile

    w0 = 10.0 * OMEGA
    dt = make(StructureLoads(T_IN, w0)).mesh_period / 32
    n_steps = 96
    w1, end = 0.97 * w0, (n_steps + 0.5) * dt  # (the steps' sum of dt ends inside the ramp)
    ramp = SpeedProfile((0.0, end), (w0, w1))
    st = make(StructureLoads(T_IN, w0, profile=ramp), gyroscopic=True)
    kb, cb, f0 = iso(1e8), iso(1e5), np.zeros((4, 2))
    st.static(f0, kb, cb)
    m, _, k, force, nl_at = monolithic_structure(st, affine(f0, kb, cb))
    sys_ = st.system
    lay = sys_.layout
    signed = lay.ratios * lay.directions
    c_damping = sys_.reduce(st.damping_full)
    inertia = -sys_.reduce(sys_.mass @ sys_.rigid_rotation(signed)) * (w1 - w0) / end

    def damping(w):
        return c_damping + sys_.reduce(sys_.gyroscopic(w * signed))

    x0 = sys_.reduce(st.full_vector("x"))
    refs = {"follows": (x0, np.zeros_like(x0), np.zeros_like(x0)),
            "frozen": (x0, np.zeros_like(x0), np.zeros_like(x0))}
    frozen_distance = 0.0
    for i in range(n_steps):
        t1 = (i + 1) * dt
        info = st.step(dt, f0, kb, cb)
        assert info.residual <= st.tol
        for name, w in (("follows", w0 + (w1 - w0) * t1 / end), ("frozen", w0)):
            x, v, a, _ = newmark_step(m, damping(w), k, dt, t1, *refs[name],
                                      lambda t: force(t) + inertia, nl_at(t1), tol=1e-9)
            refs[name] = (x, v, a)
        x, v, _ = refs["follows"]
        np.testing.assert_allclose(sys_.reduce(st.full_vector("x")), x, rtol=0,
                                   atol=1e-8 * np.abs(x).max())
        np.testing.assert_allclose(sys_.reduce(st.full_vector("v")), v, rtol=0,
                                   atol=1e-7 * np.abs(v).max())
        frozen_distance = max(frozen_distance, np.abs(refs["frozen"][1] - v).max()
                              / (1e-7 * np.abs(v).max()))
    assert frozen_distance > 10.0, frozen_distance
