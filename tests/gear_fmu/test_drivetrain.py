"""Drivetrain boundary conditions and damping models against closed forms.

The torsional checks use shafts made practically rigid (Young's modulus x 1e6) and a mesh that
acts in torsion only, ``K12 = k v v^T`` with v = r_b1 on the pinion theta and r_b2 on the gear
theta: the system is then the textbook chain of rigid inertias joined by springs, whose
frequencies are written here by hand.
"""

import math
from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg

from fmu_src.case import CaseError, load_case
from fmu_src.description import structure
from fmu_src.examples import paper_system
from gear_fmu.drivetrain import Drivetrain
from gear_fmu.modal.damping import DampingModel, damping_matrix
from gear_fmu.modal.modes import mesh_dofs, mesh_stiffness_matrix, natural_modes
from gear_fmu.system import GearShaftSystem, gear_inertias

RB = (0.05, 0.30)  # base radii [m]
K_MESH = 4e8  # mesh stiffness along the line of action [N/m]
STIFF = 1e15  # bearing springs [N/m]: rigid supports
#: Young's modulus factor of the "rigid" shafts. What remains of their torsional compliance
#: shifts the modes by up to 4.5e-4, 2.8e-5 at factors 1e4, 1e5 (converging to the closed
#: forms as 1/factor); beyond 1e5 the eigensolver's round-off (eps times the stiffest shaft
#: mode over the mode) takes over. Tolerance: 2.8e-5 measured at 1e5 (the chain with the
#: coupled motor), with a margin of 2. A misplaced inertia or spring moves them by percents.
RIGID = 1e5
RTOL = 6e-5


def rigid_system(drivetrain):
    """The paper's train (Tables 1-2: shafts 70/30 and 90/30 mm, 160 mm, steel; gears 2 and
    74 kg, 26 and 157 teeth of 4 mm, faces 50 and 40 mm) with shafts RIGID times stiffer, cut
    into 4 elements, and the given drivetrain."""
    lay = paper_system().layout
    shafts = tuple(replace(s, young=s.young * RIGID, element_length=s.length / 4)
                   for s in lay.shafts)
    return GearShaftSystem(replace(lay, shafts=shafts,
                                   drive=replace(lay.drive, drivetrain=drivetrain)))


def gear_polar_inertia(system, i):
    """Polar inertia of gear i (pinion 0, gear 1) [kg m^2]: an annulus of the pitch radius."""
    gear = system.layout.gears[i]
    return gear_inertias(gear, system.layout.shaft(gear.shaft).density)[1]


def torsion_mesh():
    v = np.zeros(12)
    v[5], v[11] = RB
    return K_MESH * np.outer(v, v)


def shaft_inertia(system, i):
    shaft = system.layout.shafts[i]
    s = shaft.section(0)
    return s.density * math.pi * (s.outer_diameter**4 - s.inner_diameter**4) / 32 * \
        shaft.length


def torsion_frequencies(system):
    """Natural frequencies [rad/s] of the free torsion DOFs (theta of every node, motor, load)
    with the mesh: the torsion block of M and K_shaft + K12, which the torsion-only mesh and
    the shafts' uncoupled torsion separate exactly from bending (the full problem would mix
    in the round-off of the stiff bending modes)."""
    t = np.intersect1d(np.flatnonzero(system.dof_kind() == 1), system.free)
    k = system.stiffness + mesh_stiffness_matrix(system, torsion_mesh())
    lam = scipy.linalg.eigh(k[np.ix_(t, t)], system.mass[np.ix_(t, t)], eigvals_only=True)
    return np.sqrt(np.clip(lam, 0.0, None))


@pytest.mark.parametrize("motor", [0.0, 0.05, 0.5])
def test_two_inertia_mesh_mode_with_a_rigid_motor_and_load(motor):
    """Rigid motor J_m on the input, rigid load J_L on the output: a rigid-body rotation and
    omega^2 = k (r_b1^2 / J1 + r_b2^2 / J2), J1 = J_m + J_pinion + J_shaft1, J2 = J_gear +
    J_L + J_shaft2."""
    load = 3.0
    sys_ = rigid_system(Drivetrain(motor_inertia=motor, output_end="load", load_inertia=load))
    j1 = motor + gear_polar_inertia(sys_, 0) + shaft_inertia(sys_, 0)
    j2 = load + gear_polar_inertia(sys_, 1) + shaft_inertia(sys_, 1)
    expected = math.sqrt(K_MESH * (RB[0] ** 2 / j1 + RB[1] ** 2 / j2))
    w = torsion_frequencies(sys_)
    assert w[0] < 1e-2 * expected  # the train's free rotation (round-off: 1e-3)
    assert w[1] == pytest.approx(expected, rel=RTOL)


def test_motor_behind_a_coupling_against_the_three_inertia_chain():
    """Motor J_m -- k_c -- pinion side J1 -- mesh -- gear side J2, output free with a load:
    the generalised eigenvalues of the 3 x 3 chain written by hand."""
    jm, kc, load = 0.2, 2e4, 3.0
    sys_ = rigid_system(Drivetrain(motor_inertia=jm, motor_coupling_stiffness=kc,
                                   output_end="load", load_inertia=load))
    j1 = gear_polar_inertia(sys_, 0) + shaft_inertia(sys_, 0)
    j2 = load + gear_polar_inertia(sys_, 1) + shaft_inertia(sys_, 1)
    r1, r2 = RB
    k = np.array([[kc, -kc, 0.0],
                  [-kc, kc + K_MESH * r1 * r1, K_MESH * r1 * r2],
                  [0.0, K_MESH * r1 * r2, K_MESH * r2 * r2]])
    lam = scipy.linalg.eigvalsh(k, np.diag([jm, j1, j2]))
    expected = np.sqrt(np.clip(lam, 0.0, None))
    w = torsion_frequencies(sys_)[:3]
    assert w[0] < 1e-2 * expected[1]  # the free rotation (round-off: 1e-3)
    np.testing.assert_allclose(w[1:], expected[1:], rtol=RTOL)


def test_clamped_output_with_a_coupled_motor():
    """Output clamped (rigid gear shaft: the gear cannot turn): J_m -- k_c -- J1 -- k r_b1^2 --
    ground."""
    jm, kc = 0.5, 5e3
    sys_ = rigid_system(Drivetrain(motor_inertia=jm, motor_coupling_stiffness=kc))
    j1 = gear_polar_inertia(sys_, 0) + shaft_inertia(sys_, 0)
    k = np.array([[kc, -kc], [-kc, kc + K_MESH * RB[0] ** 2]])
    expected = np.sqrt(scipy.linalg.eigvalsh(k, np.diag([jm, j1])))
    np.testing.assert_allclose(torsion_frequencies(sys_)[:2], expected, rtol=RTOL)


def test_mesh_damping_ratio_of_the_two_inertia_mode():
    """Mesh damping alone (no structural damping): the damped torsional mode of the rigid
    two-inertia system has the requested ratio (complex eigenvalue, closed form
    zeta = c / (2 sqrt(k m_e)))."""
    load = 3.0
    sys_ = rigid_system(Drivetrain(output_end="load", load_inertia=load))
    j = [gear_polar_inertia(sys_, i) for i in range(2)]
    model = DampingModel(ratio=0.0, mesh_ratio=0.05)
    c, _ = damping_matrix(sys_, model, torsion_mesh(), STIFF, [RB])
    # the damper's coefficient: c_m = 2 zeta sqrt(k m_e), m_e from the gear bodies only
    m_e = 1.0 / (RB[0] ** 2 / j[0] + RB[1] ** 2 / j[1])
    c_m = 2 * 0.05 * math.sqrt(K_MESH * m_e)
    theta = [5, 11]
    gdofs = mesh_dofs(sys_, 0)[theta]
    np.testing.assert_allclose(c[np.ix_(gdofs, gdofs)],
                               c_m * np.outer(RB, RB), rtol=1e-12)
    # and the eigenvalue of the 2-inertia chain with that damper (J with the shafts)
    j1 = j[0] + shaft_inertia(sys_, 0)
    j2 = j[1] + load + shaft_inertia(sys_, 1)
    kk = K_MESH * np.outer(RB, RB)
    cc = c_m * np.outer(RB, RB)
    mm = np.diag([j1, j2])
    a = np.block([[np.zeros((2, 2)), np.eye(2)],
                  [-np.linalg.solve(mm, kk), -np.linalg.solve(mm, cc)]])
    lam = np.linalg.eigvals(a)
    lam = lam[np.argmax(np.abs(lam))]
    m_chain = 1.0 / (RB[0] ** 2 / j1 + RB[1] ** 2 / j2)
    assert -lam.real / abs(lam) == pytest.approx(c_m / (2 * math.sqrt(K_MESH * m_chain)),
                                                 rel=1e-10)


def test_rayleigh_damping_has_the_ratio_at_both_frequencies():
    """Rayleigh from two natural frequencies of the basis K_shaft + K_mesh: the modal damping
    of those two modes (Phi^T C Phi / 2 omega) is the ratio."""
    sys_ = paper_system()
    k12 = torsion_mesh()
    ref = natural_modes(sys_, 0.0, k12)
    nz = np.flatnonzero(ref.omega > 1.0)
    i1, i2 = nz[2], nz[8]
    f1, f2 = ref.frequency_hz[i1], ref.frequency_hz[i2]
    model = DampingModel(kind="rayleigh", ratio=0.04, rayleigh_frequencies=(f1, f2))
    c, modes = damping_matrix(sys_, model, k12, 0.0, [RB])
    assert modes is None
    modal = ref.shapes.T @ c @ ref.shapes
    for i in (i1, i2):
        assert modal[i, i] / (2 * ref.omega[i]) == pytest.approx(0.04, rel=1e-9)
    # proportional damping: diagonal in the basis modes (measured 1e-12 of the diagonal)
    off = modal - np.diag(np.diag(modal))
    assert np.abs(off).max() <= 1e-9 * np.abs(np.diag(modal)).max()


def test_modal_damping_on_the_structure_basis():
    """basis = structure: Phi^T C Phi = diag(2 zeta omega) on the modes of K_shaft + K_mesh."""
    sys_ = paper_system()
    k12 = torsion_mesh()
    c, ref = damping_matrix(sys_, DampingModel(ratio=0.02, basis="structure"), k12, 1e9, [RB])
    basis = natural_modes(sys_, 0.0, k12)
    np.testing.assert_allclose(ref.omega, basis.omega)
    modal = basis.shapes.T @ c @ basis.shapes
    np.testing.assert_allclose(modal, np.diag(2 * 0.02 * basis.omega),
                               atol=1e-9 * basis.omega.max())


def test_load_end_balances_the_input_torque():
    """output_end = load: the resisting torque T z2/z1 balances T through the mesh, so the
    spring that fixes the free rotation in the static solution carries nothing, and the
    static state equals the clamped one up to that rotation (transmission error, mesh load)."""
    ref = structure(load_case("baguet2010_spur"))
    st = structure(load_case("baguet2010_spur", {"drive.output_end": "load",
                                                 "drive.load_inertia": "4 kg m^2"}))
    kb = np.broadcast_to(1e9 * np.eye(2), (4, 2, 2)).copy()
    for s in (ref, st):
        s.static(np.zeros((4, 2)), kb)
    x_load = st.full_vector("x")[st.system.load_dof]
    reaction = st.system.static_ground * x_load
    assert abs(reaction) <= 1e-9 * 220.0  # measured 1e-13 of T
    np.testing.assert_allclose(st.transmission_errors(), ref.transmission_errors(), rtol=1e-9)
    np.testing.assert_allclose(st.mesh_forces(), ref.mesh_forces(), rtol=1e-9)


def test_gear_inertias_can_be_given():
    case = load_case("baguet2010_spur", {"gears.pinion.polar_inertia": "0.004 kg.m^2",
                                         "gears.gear.polar_inertia": 5.0,
                                         "gears.pinion.diametral_inertia": 0.002,
                                         "gears.gear.diametral_inertia": 2.5})
    sys_ = structure(case).system
    node = mesh_dofs(sys_, 0)[6:]  # the gear's node
    gear = sys_.layout.gears[1]
    assert gear_inertias(gear, sys_.layout.shaft(gear.shaft).density) == (2.5, 5.0)
    assert sys_.mass[node[5], node[5]] >= 5.0


@pytest.mark.parametrize("overrides, words", [
    ({"drive.motor_coupling_stiffness": 1e4}, "motor_inertia must be > 0"),
    ({"drive.load_inertia": 1.0}, "output_end = 'load'"),
    ({"drive.motor_inertia": "0.1 kg"}, "inertia"),
    ({"simulation.damping_model": "rayleigh"}, "rayleigh_frequencies"),
    ({"simulation.damping_model": "rayleigh", "simulation.rayleigh_frequencies": [500, 100]},
     "0 < f1 < f2"),
    ({"simulation.mesh_damping_ratio": 0.05, "simulation.mesh_damping": 100.0}, "not both"),
])
def test_bad_drivetrain_and_damping_fields_name_the_field(overrides, words):
    with pytest.raises(CaseError, match=words.replace("(", r"\(")) as err:
        load_case("baguet2010_spur", overrides)
    key = next(iter(overrides)).split(".")[1]
    assert key.split("_")[0] in str(err.value)
