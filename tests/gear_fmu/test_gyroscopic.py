"""Gyroscopic matrices (gear_fmu.timoshenko) against closed forms and a published rotor.

* an overhung disc on a (nearly) massless cantilever: forward and backward whirl frequencies
  from the cantilever's closed-form flexibility (Timoshenko: shear in the tip deflection);
* a simply supported spinning Rayleigh beam (rotary inertia, no shear): its closed-form
  whirl frequencies, for the distributed matrix of the shaft element;
* Friswell et al. (2010), "Dynamics of Rotating Machines", Cambridge University Press,
  Example 5.9.1 (p. 206): a 1.5 m shaft with two discs on isotropic bearings, the published
  natural frequencies at 0 and 4000 rpm (6 elements), to their rounding (the issue asks 1 %).
"""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from gear_fmu.dofs import PHI, PSI, U, V
from gear_fmu.modal.whirl import whirl
from gear_fmu.timoshenko import (
    HollowSection,
    disc_gyroscopic,
    disc_matrices,
    gyroscopic_coupling,
    planar_rotary,
    planar_timoshenko,
    timoshenko_element,
    timoshenko_gyroscopic,
)

STEEL = {"young": 211e9, "density": 7810.0}


def lateral(n_nodes, clamped=()):
    """The u, v, phi, psi DOFs of n nodes, those of the ``clamped`` (node, local) left out."""
    return [6 * n + i for n in range(n_nodes) for i in (U, V, PHI, PSI)
            if (n, i) not in clamped]


def shaft(section, lengths, element=timoshenko_element, gyro=timoshenko_gyroscopic):
    """K, M, G (per unit spin) of a shaft of elements of the given lengths."""
    n = 6 * (len(lengths) + 1)
    k, m, g = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))
    for e, le in enumerate(lengths):
        sl = slice(6 * e, 6 * e + 12)
        ke, me = element(section, le)
        k[sl, sl] += ke
        m[sl, sl] += me
        g[sl, sl] += gyro(section, le)
    return k, m, g


def add_disc(m, g, node, mass, i_d, i_p):
    sl = slice(6 * node, 6 * node + 6)
    m[sl, sl] += disc_matrices(mass, i_d, i_p)
    g[sl, sl] += disc_gyroscopic(i_p)


def whirl_modes(k, m, g, spin, keep):
    """(frequencies [rad/s] ascending, shapes on the full numbering) of the oscillating modes of
    M x'' + spin G x' + K x = 0 on the DOFs ``keep``."""
    idx = np.array(keep)
    kk, mm, gg = (a[np.ix_(idx, idx)] for a in (k, m, g))
    n = idx.size
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -np.linalg.solve(mm, kk)
    a[n:, n:] = -np.linalg.solve(mm, spin * gg)
    lam, vec = np.linalg.eig(a)
    up = lam.imag > 0.0
    order = np.argsort(lam.imag[up])
    shapes = np.zeros((k.shape[0], order.size), dtype=complex)
    shapes[idx] = vec[:n, up][:, order]
    return lam.imag[up][order], shapes


#: the overhung disc (5 kg, r 150 mm, a thin disc: I_d = I_p / 2) on a massless cantilever
#: (300 mm, 25 mm solid; density 1e-6 kg/m^3: the shaft's mass 1e-12 of the disc's), and the
#: elements of its model
OVERHUNG = {"length": 0.3, "mass": 5.0, "i_p": 5.0 * 0.15**2 / 2, "i_d": 5.0 * 0.15**2 / 4}
OVERHUNG_SECTION = HollowSection(0.025, 0.0, density=1e-6)
OVERHUNG_ELEMENTS = 3


def overhung_closed_form(spin: float) -> dict:
    """``{"forward": [...], "backward": [...]}`` whirl frequencies [rad/s] of the overhung disc
    at ``spin`` [rad/s]: the tip's stiffness from the cantilever's flexibility [[L^3/3EI +
    L/kGA, L^2/2EI], [L^2/2EI, L/EI]] (exact for Timoshenko) and circular whirl at w in the
    spin's sense, (k11 - m w^2)(k22 - I_d w^2 + I_p spin w) - k12^2 = 0 (-spin backward)."""
    o, sec = OVERHUNG, OVERHUNG_SECTION
    length = o["length"]
    ei = sec.young * sec.second_moment
    kga = sec.shear_coefficient * sec.shear_modulus * sec.area
    flex = np.array([[length**3 / (3 * ei) + length / kga, length**2 / (2 * ei)],
                     [length**2 / (2 * ei), length / ei]])
    (k11, k12), (_, k22) = np.linalg.inv(flex)
    out = {}
    for sense, s in (("forward", abs(spin)), ("backward", -abs(spin))):
        poly = np.polymul([-o["mass"], 0.0, k11], [-o["i_d"], o["i_p"] * s, k22])
        poly[-1] -= k12**2
        out[sense] = sorted(r.real for r in np.roots(poly) if abs(r.imag) < 1e-9 and r.real > 0)
    return out


def overhung_model():
    """K, M, G of the overhung disc on :data:`OVERHUNG_ELEMENTS` Timoshenko elements and the
    lateral DOFs kept (the root node clamped)."""
    n = OVERHUNG_ELEMENTS
    k, m, g = shaft(OVERHUNG_SECTION, [OVERHUNG["length"] / n] * n)
    add_disc(m, g, n, OVERHUNG["mass"], OVERHUNG["i_d"], OVERHUNG["i_p"])
    return k, m, g, lateral(n + 1, clamped={(0, i) for i in (U, V, PHI, PSI)})


def friswell_rotor():
    """K, M, G of Friswell et al.'s Example 5.9.1 (module docstring; the test's docstring) and
    its lateral DOFs."""
    nu = 211e9 / (2.0 * 81.2e9) - 1.0
    s = HollowSection(0.05, 0.0, young=211e9, poisson=nu, density=7810.0)
    n_el = 6
    k, m, g = shaft(s, [1.5 / n_el] * n_el)
    for node, outer in ((2, 0.28), (4, 0.35)):
        r2 = (outer / 2) ** 2 + 0.025**2
        mass = 7810.0 * math.pi / 4 * (outer**2 - 0.05**2) * 0.07
        add_disc(m, g, node, mass, mass * r2 / 4 + mass * 0.07**2 / 12, mass * r2 / 2)
    for node in (0, n_el):
        for i in (U, V):
            k[6 * node + i, 6 * node + i] += 1e6
    return k, m, g, lateral(n_el + 1)


def test_the_gyroscopic_matrices_are_skew_and_the_disc_holds_its_polar_inertia():
    s = HollowSection(0.07, 0.03)
    g = timoshenko_gyroscopic(s, 0.02)
    assert np.array_equal(g, -g.T)
    d = disc_gyroscopic(4.5)
    assert d[PHI, PSI] == 4.5 and d[PSI, PHI] == -4.5
    assert np.count_nonzero(d) == 2
    # a shaft element's rotations carry rho J = 2 rho I: G's blocks are twice M's rotary part
    ei = s.young * s.second_moment
    kga = s.shear_coefficient * s.shear_modulus * s.area
    _, m_rot = planar_timoshenko(0.02, ei, kga, 0.0, 1.0)
    assert np.allclose(planar_rotary(0.02, ei, kga), m_rot, rtol=1e-14, atol=0.0)


@pytest.mark.parametrize("spin", [0.0, 300.0, 1500.0, -800.0])
def test_overhung_disc_on_a_massless_cantilever_whirls_as_the_closed_form(spin):
    """Tip disc m, I_d, I_p on a cantilever of tip flexibility [[L^3/3EI + L/kGA, L^2/2EI],
    [L^2/2EI, L/EI]] (exact for Timoshenko); circular whirl at w in the spin's sense:
    (k11 - m w^2)(k22 - I_d w^2 + I_p spin w) - k12^2 = 0, against it with -spin."""
    expected = overhung_closed_form(spin)
    k, m, g, keep = overhung_model()
    freq, shapes = whirl_modes(k, m, g, spin, keep)
    nodes = SimpleNamespace(n_nodes=OVERHUNG_ELEMENTS + 1,
                            node_shaft=np.zeros(OVERHUNG_ELEMENTS + 1, dtype=int), mass=m)
    _, labels = whirl(nodes, shapes[:, :4], [np.sign(spin) or 1.0])
    want = sorted(expected["forward"] + expected["backward"])
    assert len(want) == 4
    assert np.allclose(freq[:4], want, rtol=1e-7, atol=0.0)  # measured 1e-9: eig round-off
    if spin != 0.0:  # at rest the pairs coincide and any combination is a mode
        for f, label in zip(freq[:4], labels, strict=True):
            sense = min(expected, key=lambda key: min(abs(np.array(expected[key]) - f)))
            assert label == sense, (f, label, expected)


def test_simply_supported_spinning_rayleigh_beam_whirls_as_the_closed_form():
    """Uniform beam, rotary inertia, no shear, spin W: mode j (k = j pi / L) whirls at w with
    EI k^4 - rho A w^2 - rho I k^2 w^2 +- rho J W w k^2 = 0 (+ forward). 40 elements: the
    first two modes to 1e-6."""
    length, spin = 1.2, 2000.0
    s = HollowSection(0.06, 0.02)
    ei, rho_a, rho_i = s.young * s.second_moment, s.density * s.area, s.density * s.second_moment
    rho_j = 2.0 * rho_i

    def element(_, le):
        kp, mp = planar_timoshenko(le, ei, math.inf, rho_a, rho_i)
        k, m = np.zeros((12, 12)), np.zeros((12, 12))
        for idx, t in (([U, PSI, 6 + U, 6 + PSI], np.eye(4)),
                       ([V, PHI, 6 + V, 6 + PHI], np.diag([1.0, -1.0, 1.0, -1.0]))):
            k[np.ix_(idx, idx)] = t @ kp @ t
            m[np.ix_(idx, idx)] = t @ mp @ t
        return k, m

    def gyro(_, le):
        return gyroscopic_coupling(planar_rotary(le, ei, math.inf), rho_j, 2)

    n_el = 40
    k, m, g = shaft(s, [length / n_el] * n_el, element, gyro)
    keep = lateral(n_el + 1, clamped={(0, U), (0, V), (n_el, U), (n_el, V)})
    freq, _ = whirl_modes(k, m, g, spin, keep)
    want = []
    for j in (1, 2):
        kj = j * math.pi / length
        for sign in (1.0, -1.0):
            roots = np.roots([-(rho_a + rho_i * kj**2), sign * rho_j * spin * kj**2, ei * kj**4])
            want.append(max(roots.real))
    assert np.allclose(freq[:4], sorted(want), rtol=1e-6, atol=0.0)


FRISWELL_0 = [86.66, 86.66, 274.31, 274.31, 716.78, 716.78]  # rad/s, at rest
FRISWELL_4000 = [85.39, 87.80, 251.78, 294.71, 600.18, 827.08]  # rad/s, at 4000 rpm


@pytest.mark.parametrize(("rpm", "published"), [(0.0, FRISWELL_0), (4000.0, FRISWELL_4000)])
def test_friswell_example_5_9_1_to_one_percent(rpm, published):
    """Shaft 1.5 m, solid 50 mm, E = 211 GPa, G = 81.2 GPa, rho = 7810 kg/m^3, six equal
    Timoshenko elements; discs 70 mm wide on a 50 mm bore, 280 mm at 0.5 m and 350 mm at 1 m;
    bearings 1 MN/m at both ends, undamped."""
    k, m, g, keep = friswell_rotor()
    freq, _ = whirl_modes(k, m, g, rpm * math.pi / 30.0, keep)
    # the table rounds to 0.01 rad/s (6e-5 of 85 rad/s); measured within 4.7e-5 of it
    assert np.allclose(freq[:6], published, rtol=2e-4, atol=0.0), freq[:6]
