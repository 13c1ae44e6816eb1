"""Modes of the paper's two-shaft system and the modal damping matrix."""

import math

import numpy as np
import pytest
import scipy.linalg

from fmu_src.examples import paper_system
from gear_fmu.modal.modes import (
    bearing_stiffness_matrix,
    mesh_dofs,
    modal_damping_matrix,
    mode_table,
    natural_modes,
)
from gear_fmu.system import gear_inertias

SYSTEM = paper_system(n_elements=8)
LAYOUT = SYSTEM.layout
STIFF = 1e13  # N/m: practically rigid bearings


def gear_polar_inertia(i):
    """Polar inertia of gear i of the paper's layout (pinion 0, gear 1) [kg m^2]."""
    gear = LAYOUT.gears[i]
    return gear_inertias(gear, LAYOUT.shaft(gear.shaft).density)[1]


def test_modes_are_mass_normalised_eigenpairs_with_energy_shares():
    modes = natural_modes(SYSTEM, 1e8)
    m, phi = SYSTEM.mass, modes.shapes
    np.testing.assert_allclose(phi.T @ m @ phi, np.eye(phi.shape[1]), atol=1e-9)
    k = SYSTEM.stiffness + bearing_stiffness_matrix(SYSTEM, 1e8)
    res = k @ phi - m @ phi * modes.omega**2
    assert np.abs(res[SYSTEM.free]).max() <= 1e-7 * np.abs(k @ phi).max()
    np.testing.assert_allclose(modes.kinetic_fraction.sum(axis=1), 1.0, rtol=1e-12)
    assert np.all(modes.shapes[SYSTEM.output_dof] == 0.0)  # clamped output torsion


def test_gear_shaft_torsion_mode_against_lumped_inertia_formula():
    """Without mesh: pinion shaft torsion is a free rigid mode; gear shaft torsion: clamped half
    shaft (k = G J / (L/2)) carrying the gear's Ip plus the free half shaft (Rayleigh: 1/3 of the
    clamped half's inertia)."""
    modes = natural_modes(SYSTEM, STIFF)
    # a rigid mode is zero to the round-off of the eigensolver: sqrt(eps) * omega_max
    round_off = math.sqrt(np.finfo(float).eps) * modes.omega[-1]
    assert modes.omega[0] < round_off < 1e-3 * modes.omega[1]
    assert modes.kinds[0] == "torsion"
    shaft = LAYOUT.shafts[1]
    s = shaft.section(0)
    half = shaft.length / 2
    ip = gear_polar_inertia(1)
    rho_j = s.density * s.polar_moment
    w = math.sqrt(s.shear_modulus * s.polar_moment / half / (ip + rho_j * half * (1 + 1 / 3)))
    tors = [om for om, kd in zip(modes.omega, modes.kinds, strict=True) if kd == "torsion"]
    assert tors[1] == pytest.approx(w, rel=2e-3)
    print(f"\ngear-shaft torsion mode {tors[1] / 2 / math.pi:.1f} Hz "
          f"(lumped {w / 2 / math.pi:.1f})")


def test_gear_shaft_bending_mode_against_rayleigh_estimate():
    """Stiff bearings: gear disc at mid-span of a simply supported Timoshenko shaft;
    k = 1 / (L^3 / 48 EI + L / 4 kGA), m = M_gear + 17/35 m_shaft (Rayleigh)."""
    modes = natural_modes(SYSTEM, STIFF)
    shaft = LAYOUT.shafts[1]
    s = shaft.section(0)
    L = shaft.length
    k = 1 / (L**3 / (48 * s.young * s.second_moment)
             + L / (4 * s.shear_coefficient * s.shear_modulus * s.area))
    w = math.sqrt(k / (LAYOUT.gears[1].mass + 17 / 35 * shaft.mass))
    # lowest modes where the gear's translation holds most of the kinetic energy (the gear's
    # rocking mode, rotation about a diameter, comes first and is not this one)
    g = mesh_dofs(SYSTEM, 0)[6:8]  # the gear's u, v
    share = LAYOUT.gears[1].mass * (modes.shapes[g] ** 2).sum(axis=0)
    trans = modes.omega[share > 0.5]
    assert trans[0] == pytest.approx(w, rel=1e-2)
    assert trans[1] == pytest.approx(trans[0], rel=1e-9)  # s and t planes
    print(f"\ngear translation mode {trans[0] / 2 / math.pi:.1f} Hz (Rayleigh "
          f"{w / 2 / math.pi:.1f} Hz)")


def test_modal_damping_gives_the_damping_factor_on_every_mode():
    """Phi^T C Phi = diag(2 zeta omega); the damped eigenvalues have ratio zeta."""
    zeta = 0.03
    mesh_k = np.zeros((12, 12))
    n = np.array([math.sin(math.radians(20)), math.cos(math.radians(20)), 0.0])
    r1, r2 = 0.052, 0.314
    v = np.concatenate([n, np.cross([r1, 0, 0], n), -n, -np.cross([-r2, 0, 0], n)])
    mesh_k += 5e8 * np.outer(v, v)
    modes = natural_modes(SYSTEM, 1e8, mesh_k)
    c = modal_damping_matrix(SYSTEM, modes, zeta)
    np.testing.assert_allclose(modes.shapes.T @ c @ modes.shapes, np.diag(2 * zeta * modes.omega),
                               atol=1e-9 * modes.omega.max())
    f = SYSTEM.free
    m_r, c_r = SYSTEM.reduce(SYSTEM.mass), SYSTEM.reduce(c)
    k_r = SYSTEM.reduce(SYSTEM.stiffness + bearing_stiffness_matrix(SYSTEM, 1e8))
    k_r[np.ix_(*[np.searchsorted(f, mesh_dofs(SYSTEM, 0))] * 2)] += mesh_k
    nr = f.size
    a = np.block([[np.zeros((nr, nr)), np.eye(nr)],
                  [-np.linalg.solve(m_r, k_r), -np.linalg.solve(m_r, c_r)]])
    lam = scipy.linalg.eigvals(a)
    lam = lam[lam.imag > 1.0]
    ratio = -lam.real / np.abs(lam)
    np.testing.assert_allclose(ratio, zeta, rtol=1e-5)
    # the mesh couples torsion and bending: at least one mixed mode carrying mesh strain
    assert any("-" in kd for kd in modes.kinds)
    assert modes.mesh_energy_fraction.max() > 0.3


def test_mode_table_lists_frequencies_and_types():
    modes = natural_modes(SYSTEM, 1e8)
    table = mode_table(modes, 6)
    lines = table.splitlines()
    assert len(lines) == 7
    assert f"{modes.frequency_hz[3]:.2f}" in lines[4]
    print("\n" + table)


def test_bad_input():
    with pytest.raises(ValueError, match="bearing stiffness shape"):
        bearing_stiffness_matrix(SYSTEM, np.zeros((3, 2, 2)))
    with pytest.raises(ValueError, match="zeta"):
        modal_damping_matrix(SYSTEM, natural_modes(SYSTEM, 1e8), 1.5)
    with pytest.raises(ValueError, match="mesh stiffness shape"):
        natural_modes(SYSTEM, 1e8, np.zeros((2, 12, 12)))  # one mesh in the paper's train


def test_the_nodes_follow_the_layout_whatever_the_element_length():
    """The shafts' nodes follow the layout: with elements no longer than L/7 (the old
    two-shaft model took an element count, and refused an odd one: its gears sat on the mid
    node), each of the paper's shafts still gets a node under its gear at mid-span and at each
    bearing, each half cut into 4 equal elements (9 nodes a shaft)."""
    sys_ = paper_system(n_elements=7)
    for g, node in zip(sys_.layout.gears, sys_.gear_nodes, strict=True):
        assert sys_.node_position[node] == pytest.approx(g.position, abs=1e-12)
    for b, node in zip(sys_.layout.bearings, sys_.bearing_nodes, strict=True):
        assert sys_.node_position[node] == pytest.approx(b.position, abs=1e-12)
    for shaft, nodes in zip(sys_.layout.shafts, sys_.shaft_nodes, strict=True):
        assert nodes.size == 9
        assert np.diff(sys_.node_position[nodes]).max() <= shaft.length / 7
