"""Static equilibrium (Eq. 8), the linearised 8-coefficient law (Eq. 17) and the lumped spring."""

import math

import numpy as np
import pytest

from bearing_fmu import BearingData, EccentricityError
from bearing_fmu.linear import LinearBearing
from bearing_fmu.lumped import LumpedSpringBearing
from bearing_fmu.short_bearing import ShortBearing, ocvirk_static_force
from bearing_fmu.static import static_equilibrium

BEARING = BearingData(diameter=0.070, length=0.050, clearance=150e-6, viscosity=0.0288)
OMEGA = 325.0


@pytest.mark.parametrize("load", [(0.0, -2251.0), (1500.0, 400.0), (-10.0, 5.0)])
def test_static_equilibrium_balances_the_load(load):
    sol = static_equilibrium(ShortBearing(BEARING), load, OMEGA)
    np.testing.assert_allclose(sol.result.force, -np.asarray(load), rtol=0, atol=1e-9 * 2251)


def test_static_eccentricity_and_attitude_match_ocvirk_closed_form():
    """Ocvirk: |Fbar(eps)| from the closed form, attitude tan(phi) = pi sqrt(1-eps^2) / (4 eps)."""
    sol = static_equilibrium(ShortBearing(BEARING), (0.0, -2000.0), OMEGA)
    fx, fy = ocvirk_static_force(BEARING.lambda_, sol.eccentricity)
    assert math.hypot(fx, fy) * BEARING.force_scale(OMEGA) == pytest.approx(2000.0, rel=1e-10)
    eps = sol.eccentricity
    phi = math.degrees(math.atan(math.pi * math.sqrt(1 - eps**2) / (4 * eps)))
    assert sol.attitude_deg == pytest.approx(phi, abs=1e-8)


def test_overload_is_a_clear_error():
    with pytest.raises(EccentricityError, match="cannot carry"):
        static_equilibrium(ShortBearing(BEARING), (0.0, -1e9), OMEGA)


def test_linear_bearing_reproduces_linearisation_and_converges_in_one_step():
    short = ShortBearing(BEARING)
    sol = static_equilibrium(short, (0.0, -2251.0), OMEGA)
    lin = LinearBearing.linearise(short, sol.x0, sol.y0, OMEGA)
    # at X0: the same force and coefficients (to round-off relative to |F|: the law is stored
    # as F0 + Kb X0 - Kb X, bearing_fmu.affine, and one component of F is ~0 here)
    r0 = lin.evaluate(sol.x0, sol.y0, 0.0, 0.0, OMEGA)
    np.testing.assert_allclose(r0.force, sol.result.force, rtol=0,
                               atol=1e-13 * np.hypot(*sol.result.force))
    # Eq. (17) is the first-order expansion: the gap to the nonlinear law is second order
    gaps = []
    for scale in (1.0, 0.5, 0.25):
        dx, dv = 2e-6 * scale, 2e-4 * scale
        rl = lin.evaluate(sol.x0 + dx, sol.y0 - dx, dv, -dv, OMEGA)
        rn = short.evaluate(sol.x0 + dx, sol.y0 - dx, dv, -dv, OMEGA)
        gaps.append(np.abs(rl.force - rn.force).max())
    ratios = np.array(gaps[:-1]) / np.array(gaps[1:])
    np.testing.assert_allclose(ratios, 4.0, rtol=0.1)
    # affine law: Newton converges in one step (the second evaluation only confirms)
    s2 = static_equilibrium(lin, (0.0, -2251.0), OMEGA)
    assert s2.iterations == 2
    assert s2.x0 == pytest.approx(sol.x0, rel=1e-10)
    with pytest.raises(ValueError, match="omega"):
        lin.evaluate(sol.x0, sol.y0, 0.0, 0.0, 2 * OMEGA)


def test_lumped_spring():
    model = LumpedSpringBearing(BEARING, stiffness=2e8, damping=1e3)
    r = model.evaluate(1e-6, -2e-6, 1e-3, 0.0, OMEGA)
    np.testing.assert_allclose(r.force, [-200.0 - 1.0, 400.0])
    sol = static_equilibrium(model, (0.0, -1000.0), OMEGA)
    assert sol.y0 == pytest.approx(-5e-6, rel=1e-12)
    with pytest.raises(ValueError, match="stiffness"):
        LumpedSpringBearing(BEARING, stiffness=-1.0)


def test_relinearise_is_the_mismatch_and_linearisation_of_the_master():
    """``AffineLaws.relinearise`` (one compiled call) against the numpy expressions the master
    used before it: the law of ``linearise`` and the mismatch, the 2-norm ratio
    ``sqrt(np.sum(d * d)) / sqrt(np.sum(F * F))``, ``d = F - law.force(X)``, both bit for bit
    over 2,000 draws of 1 to 6 bearings (four, as in the gear system, in three draws of four)
    and 200 of up to 80 (the sums of squares past numpy's 8-value blocks). (It was compared
    with ``np.linalg.norm``'s ratio within 6e-16 for other counts than four, 4.6e-16 measured:
    a bound on the round-off of BLAS's dot against numpy's pairwise sum, not argued; the
    ratio of the same sums, bit for bit for every count, is what the master computed.)"""
    from bearing_fmu.affine import AffineLaws

    rng = np.random.default_rng(7)
    for i in range(2200):
        nb = (4 if i % 4 else int(rng.integers(1, 7))) if i < 2000 else int(rng.integers(1, 81))
        states = rng.normal(size=(nb, 4)) * [1e-5, 1e-5, 1e-3, 1e-3]
        old = AffineLaws.linearise(rng.normal(size=(nb, 4)) * 1e-5,
                                   rng.normal(size=(nb, 2)) * 1e3,
                                   rng.normal(size=(nb, 2, 2)) * 1e8,
                                   rng.normal(size=(nb, 2, 2)) * 1e5)
        force = rng.normal(size=(nb, 2)) * 1e3
        kb, cb = rng.normal(size=(nb, 2, 2)) * 1e8, rng.normal(size=(nb, 2, 2)) * 1e5
        mismatch, new = old.relinearise(states, force, kb, cb)
        ref = AffineLaws.linearise(states, force, kb, cb)
        for got, want in ((new.f0, ref.f0), (new.kb, kb), (new.cb, cb), (new.states, states),
                          (new.force_at, force)):
            assert np.array_equal(got, want)
        diff = force - old.force(states)
        assert mismatch == (math.sqrt(float(np.sum(diff * diff)))
                            / math.sqrt(float(np.sum(force * force)))), nb


def test_the_gear_fmu_inputs_carry_the_masters_laws_bit_for_bit():
    """``pack_laws`` then ``unpack_law_arrays`` (the 56 law inputs of the gear-shaft FMU, both
    compiled) against ``AffineLaws.linearise`` (numpy), over 2,000 draws spanning 18 decades:
    f0, Kb and Cb equal bit for bit, for a law with its expansion point and for one given by
    f0 alone (expanded about X = 0)."""
    from bearing_fmu.affine import AffineLaws
    from fmu_src.contract import pack_laws, unpack_law_arrays

    rng = np.random.default_rng(11)
    packed = np.empty(56)
    for _ in range(2000):
        scale = 10.0 ** rng.uniform(-9.0, 9.0, size=4)
        law = AffineLaws.linearise(rng.normal(size=(4, 4)) * scale[0],
                                   rng.normal(size=(4, 2)) * scale[1],
                                   rng.normal(size=(4, 2, 2)) * scale[2],
                                   rng.normal(size=(4, 2, 2)) * scale[3])
        for sent in (law, AffineLaws(law.f0, law.kb, law.cb)):
            pack_laws(sent, packed)
            f0, kb, cb = unpack_law_arrays(packed.tolist())
            assert np.array_equal(kb, law.kb) and np.array_equal(cb, law.cb)
            assert np.array_equal(f0, sent.f0)
