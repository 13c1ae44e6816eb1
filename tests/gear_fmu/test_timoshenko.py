"""Timoshenko shaft element against closed forms (Timoshenko, Euler-Bernoulli, rods)."""

import math

import numpy as np
import pytest
import scipy.linalg

from gear_fmu.dofs import PHI, PSI, THETA, U, V, W
from gear_fmu.timoshenko import (
    HollowSection,
    cowper_shear_coefficient,
    disc_matrices,
    planar_timoshenko,
    timoshenko_element,
)

SECTION = HollowSection(0.070, 0.030)  # pinion shaft, Table 2
STOCKY, SLENDER = 0.16, 1.4  # m: L/D = 2.3 (the paper's shaft) and 20


def assemble(section, length, n):
    """Global K, M of a uniform shaft of n elements (6 DOFs per node)."""
    ndof = 6 * (n + 1)
    k = np.zeros((ndof, ndof))
    m = np.zeros((ndof, ndof))
    ke, me = timoshenko_element(section, length / n)
    for e in range(n):
        sl = slice(6 * e, 6 * e + 12)
        k[sl, sl] += ke
        m[sl, sl] += me
    return k, m


def assemble_planar(section, length, n, euler_bernoulli=False):
    """Planar (deflection, rotation) model: Timoshenko, or the Euler-Bernoulli limit."""
    s = section
    kga = math.inf if euler_bernoulli else s.shear_coefficient * s.shear_modulus * s.area
    rho_i = 0.0 if euler_bernoulli else s.density * s.second_moment
    ke, me = planar_timoshenko(length / n, s.young * s.second_moment, kga,
                               s.density * s.area, rho_i)
    ndof = 2 * (n + 1)
    k = np.zeros((ndof, ndof))
    m = np.zeros((ndof, ndof))
    for e in range(n):
        sl = slice(2 * e, 2 * e + 4)
        k[sl, sl] += ke
        m[sl, sl] += me
    return k, m


def frequencies(k, m, fixed=()):
    free = np.setdiff1d(np.arange(k.shape[0]), fixed)
    lam = scipy.linalg.eigh(k[np.ix_(free, free)], m[np.ix_(free, free)], eigvals_only=True)
    return np.sqrt(np.clip(lam, 0.0, None))


def timoshenko_ss_exact(section, length, n_modes):
    """Simply supported Timoshenko beam: both roots of the frequency equation per wavenumber.

    With w = W sin(k z), r = R cos(k z), k = m pi / L, the equations
    rho A w_tt = kGA (w'' - r'), rho I r_tt = EI r'' + kGA (w' - r) give
    (kGA k^2 - rho A w^2)(EI k^2 + kGA - rho I w^2) = (kGA k)^2; m = 0 adds the pure shear
    mode w = 0, r = const, w^2 = kGA / (rho I).
    """
    s = section
    ei, rho_a, rho_i = s.young * s.second_moment, s.density * s.area, s.density * s.second_moment
    kga = s.shear_coefficient * s.shear_modulus * s.area
    out = [math.sqrt(kga / rho_i)]
    for mode in range(1, n_modes + 1):
        kk = mode * math.pi / length
        a = rho_a * rho_i
        b = -(rho_a * (ei * kk**2 + kga) + rho_i * kga * kk**2)
        c = kga * kk**2 * (ei * kk**2 + kga) - (kga * kk) ** 2
        d = math.sqrt(b * b - 4 * a * c)
        out += [math.sqrt((-b - d) / (2 * a)), math.sqrt((-b + d) / (2 * a))]
    return np.sort(out)


def observed_order(errors):
    """log2 of successive error ratios (mesh halved each time)."""
    e = np.abs(np.asarray(errors))
    return np.log2(e[:-1] / e[1:])


def test_planar_stiffness_matches_przemieniecki_closed_form():
    length, ei, kga = 0.02, 2.0e5, 3.0e8
    phi = 12 * ei / (kga * length**2)
    k, _ = planar_timoshenko(length, ei, kga, 10.0, 0.01)
    L = length
    closed = ei / (L**3 * (1 + phi)) * np.array([
        [12, 6 * L, -12, 6 * L],
        [6 * L, (4 + phi) * L**2, -6 * L, (2 - phi) * L**2],
        [-12, -6 * L, 12, -6 * L],
        [6 * L, (2 - phi) * L**2, -6 * L, (4 + phi) * L**2],
    ])
    np.testing.assert_allclose(k, closed, rtol=1e-12, atol=1e-12 * np.abs(closed).max())


def test_euler_bernoulli_limit_is_the_hermite_element():
    L, rho_a = 0.3, 12.0
    _, m = planar_timoshenko(L, 1.0, math.inf, rho_a, 0.0)
    hermite = rho_a * L / 420 * np.array([
        [156, 22 * L, 54, -13 * L],
        [22 * L, 4 * L**2, 13 * L, -3 * L**2],
        [54, 13 * L, 156, -22 * L],
        [-13 * L, -3 * L**2, -22 * L, 4 * L**2],
    ])
    np.testing.assert_allclose(m, hermite, rtol=1e-12, atol=1e-14)


def test_rigid_body_motions_cost_no_strain_and_carry_the_right_inertia():
    """Rigid rotations about s and t fix the sign coupling u-psi (+) and v-phi (-)."""
    L = 0.05
    k, m = timoshenko_element(SECTION, L)
    z = np.array([-L / 2, L / 2])
    rigid = np.zeros((12, 6))
    for node in range(2):
        o = 6 * node
        rigid[o + U, 0] = rigid[o + V, 1] = rigid[o + W, 2] = 1.0
        rigid[o + PHI, 3], rigid[o + V, 3] = 1.0, -z[node]  # rotation about s: v = -phi z
        rigid[o + PSI, 4], rigid[o + U, 4] = 1.0, z[node]  # rotation about t: u = +psi z
        rigid[o + THETA, 5] = 1.0
    assert np.abs(k @ rigid).max() <= 1e-9 * np.abs(k).max() * L
    s = SECTION
    mass = s.density * s.area * L
    kinetic = rigid.T @ m @ rigid
    np.testing.assert_allclose(np.diag(kinetic)[:3], mass, rtol=1e-12)
    # about a diameter through the centre: rho I L + rho A L^3 / 12 (rotary + translational)
    i_d = s.density * s.second_moment * L + mass * L**2 / 12
    np.testing.assert_allclose(np.diag(kinetic)[3:5], i_d, rtol=1e-12)
    np.testing.assert_allclose(kinetic[5, 5], s.density * s.polar_moment * L, rtol=1e-12)
    # a wrong sign (v = +phi z) would strain the element
    wrong = rigid[:, 3].copy()
    wrong[[V, 6 + V]] *= -1
    assert np.linalg.norm(k @ wrong) > 1e3 * np.linalg.norm(k @ rigid[:, 3]) + 1.0


@pytest.mark.parametrize("length", [STOCKY, SLENDER])
def test_simply_supported_3d_shaft_matches_timoshenko_and_rods(length):
    """u = v = 0 at both ends, w and theta clamped at z = 0: bending pairs + fixed-free rods."""
    n = 16
    k, m = assemble(SECTION, length, n)
    fixed = [U, V, W, THETA, 6 * n + U, 6 * n + V]
    fe = frequencies(k, m, fixed)[:8]
    s = SECTION
    bending = timoshenko_ss_exact(s, length, 10)
    rod = np.array([(2 * j - 1) * math.pi / (2 * length) for j in range(1, 5)])
    exact = np.sort(np.concatenate([
        bending, bending,
        rod * math.sqrt(s.young / s.density), rod * math.sqrt(s.shear_modulus / s.density),
    ]))[:8]
    np.testing.assert_allclose(fe, exact, rtol=5e-3)
    # the two bending planes give identical frequencies
    pairs = frequencies(k, m, fixed)
    assert np.min(np.abs(pairs[1:] - pairs[:-1]) / pairs[1:]) < 1e-10


def test_timoshenko_convergence_order_stocky_and_slender():
    s = SECTION
    out = {}
    for length in (STOCKY, SLENDER):
        exact = timoshenko_ss_exact(s, length, 4)[:2]
        errs = []
        for n in (8, 16, 32, 64):
            k, mm = assemble_planar(s, length, n)
            errs.append((frequencies(k, mm, [0, 2 * n])[:2] - exact) / exact)
        errs = np.array(errs)
        assert np.all(errs > 0.0)  # consistent mass: Rayleigh-Ritz upper bounds
        out[length] = [observed_order(errs[:, j]) for j in range(2)]
    print(f"\nobserved orders (SS Timoshenko, modes 1-2): stocky {out[STOCKY]}, "
          f"slender {out[SLENDER]}")
    for length in out:
        for orders in out[length]:
            assert 1.8 <= orders[-1] <= 2.3
    assert np.all(np.abs(errs[-1]) < 2e-4)


def test_euler_bernoulli_limit_converges_at_order_four():
    s = SECTION
    exact = np.array([(j * math.pi / SLENDER) ** 2 for j in (1, 2)]) * math.sqrt(
        s.young * s.second_moment / (s.density * s.area))
    errs = []
    for n in (4, 8, 16):
        k, mm = assemble_planar(s, SLENDER, n, euler_bernoulli=True)
        errs.append((frequencies(k, mm, [0, 2 * n])[:2] - exact) / exact)
    orders = [observed_order(np.array(errs)[:, j]) for j in range(2)]
    print(f"\nobserved orders (SS Euler-Bernoulli limit): {orders}")
    assert all(o[-1] >= 3.8 for o in orders)


def test_free_free_slender_shaft_against_euler_bernoulli_and_rods():
    """Free-free: 6 rigid modes, bending pairs near EB (beta L = 4.7300, 7.8532), rods n pi/L."""
    length = 3.5  # L/D = 50: shear and rotary inertia below 0.5 %
    n = 24
    k, m = assemble(SECTION, length, n)
    fe = frequencies(k, m)
    s = SECTION
    assert np.all(fe[:6] < 1e-3 * fe[6])
    beta_l = np.array([4.730040745, 7.853204624])
    eb = beta_l**2 / length**2 * math.sqrt(s.young * s.second_moment / (s.density * s.area))
    flex = fe[6:]
    for w in eb:
        got = flex[np.argmin(np.abs(flex - w))]
        assert got == pytest.approx(w, rel=5e-3)
        assert got < w  # shear and rotary inertia lower the frequency
    for speed in (math.sqrt(s.young / s.density), math.sqrt(s.shear_modulus / s.density)):
        errs = []
        for nel in (4, 8, 16):
            kk, mm = assemble(SECTION, length, nel)
            f = frequencies(kk, mm)[6:]
            w = math.pi / length * speed
            errs.append(f[np.argmin(np.abs(f - w))] / w - 1.0)
        assert abs(errs[-1]) < 2e-3
        assert observed_order(errs)[-1] == pytest.approx(2.0, abs=0.1)


def test_cowper_shear_coefficient_limits():
    nu = 0.3
    assert cowper_shear_coefficient(nu, 0.0) == pytest.approx(6 * (1 + nu) / (7 + 6 * nu))
    assert cowper_shear_coefficient(nu, 0.999) == pytest.approx(
        2 * (1 + nu) / (4 + 3 * nu), rel=1e-4)
    assert 2 * (1 + nu) / (4 + 3 * nu) < SECTION.shear_coefficient < 6 * (1 + nu) / (7 + 6 * nu)


def test_bad_input_is_rejected_with_the_value():
    with pytest.raises(ValueError, match="inner_diameter"):
        HollowSection(0.03, 0.07)
    with pytest.raises(ValueError, match="element length"):
        timoshenko_element(SECTION, 0.0)
    with pytest.raises(ValueError, match="mass"):
        disc_matrices(-1.0, 1.0, 1.0)
