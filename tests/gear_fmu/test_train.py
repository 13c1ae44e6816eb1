"""Gear trains of any layout against what is known of them without the code: static
equilibrium, the torque chain, rotation invariance, the thrust of a helical driver, a lumped
torsional chain, the paper's pair built in another order, Newmark's order on two stages.

The trains are built here from :mod:`gear_fmu.layout` directly (three shafts, two stages, the
second stage's line of centres turned), so that these checks hold whatever the case files say.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg

from gear_fmu.dofs import DOF_PER_NODE, THETA, W, dof
from gear_fmu.layout import (
    BearingSpec,
    DiscSpec,
    Drive,
    GearSpec,
    Layout,
    MeshSpec,
    ShaftSpec,
)
from gear_fmu.loads import StructureLoads
from gear_fmu.mesh.geometry import zero_backlash_centre_distance
from gear_fmu.mesh.train import mesh_elements
from gear_fmu.modal import analyses
from gear_fmu.structure import Structure
from gear_fmu.system import GearShaftSystem

ALPHA = math.radians(20.0)
STIFF = 1e9  # isotropic bearing springs of the static checks [N/m]


def two_stage(direction=1.2217304763960306, helix=0.0, hands=("left", "right"),
              diameter=0.06, density=7800.0, gravity=(0.0, 0.0), stiff_supports=False,
              reverse=False, element_length=0.01):
    """Three shafts a -> b -> c, stages m1 (g1, g2) and m2 (g3, g4; its line of centres at
    ``direction`` = 70 deg by default), a disc on a; with
    ``stiff_supports`` the bearings sit next to the gears (for the torsional chain)."""
    mat = dict(young=210e9, poisson=0.3, density=density, element_length=element_length)
    lengths, offsets = (0.1, 0.12, 0.1), (0.0, 0.02, 0.06)  # the meshing faces aligned
    shafts = [ShaftSpec(n, (ln,), (diameter,), (0.0,), offset=z, **mat)
              for n, ln, z in zip("abc", lengths, offsets, strict=True)]
    beta = math.radians(helix)
    hand = hands if helix else ("", "")
    a1 = zero_backlash_centre_distance((20, 40), 4e-3, ALPHA, beta, (0.0, 0.0))
    a2 = zero_backlash_centre_distance((25, 50), 4e-3, ALPHA, 0.0, (0.0, 0.0))
    gear = dict(module=4e-3, pressure_angle=ALPHA, face_width=0.03)
    gears = [GearSpec("g1", "a", 0.05, 20, mass=1.0, helix_angle=beta, hand=hand[0],
                      polar_inertia=2e-3, diametral_inertia=1e-3, **gear),
             GearSpec("g2", "b", 0.03, 40, mass=4.0, helix_angle=beta, hand=hand[1],
                      polar_inertia=2e-2, diametral_inertia=1e-2, **gear),
             GearSpec("g3", "b", 0.09, 25, mass=1.5, polar_inertia=5e-3,
                      diametral_inertia=2.5e-3, **gear),
             GearSpec("g4", "c", 0.05, 50, mass=6.0, polar_inertia=6e-2,
                      diametral_inertia=3e-2, **gear)]
    meshes = [MeshSpec("m1", ("g1", "g2"), a1), MeshSpec("m2", ("g3", "g4"), a2,
                                                         direction=direction)]
    places = {"a": (0.025, 0.075), "b": (0.005, 0.055, 0.065, 0.115), "c": (0.025, 0.075)} \
        if stiff_supports else {"a": (0.0, 0.09), "b": (0.0, 0.12), "c": (0.0, 0.1)}
    bearings = [BearingSpec(f"{s}{k + 1}", s, p, "lumped", diameter, 0.01, 50e-6, 0.02)
                for s in "abc" for k, p in enumerate(places[s])]
    discs = [DiscSpec("hub", "a", 0.1, 0.8, 1e-3, 6e-4)] if not stiff_supports else []
    if reverse:
        shafts, bearings = shafts[::-1], bearings[::-1]
    return Layout(tuple(shafts), tuple(gears), tuple(meshes), tuple(bearings),
                  Drive("a", "c", 100.0, 120.0, output_position=0.1, gravity=gravity),
                  tuple(discs))


def structure(layout, **kw) -> Structure:
    d = layout.drive
    loads = StructureLoads(d.torque, d.speed, tuple(d.gravity) if any(d.gravity) else None)
    return Structure(GearShaftSystem(layout), mesh_elements(layout), loads, **kw)


def static(st, stiffness=STIFF) -> None:
    nb = st.nb
    st.static(np.zeros((nb, 2)), np.broadcast_to(stiffness * np.eye(2), (nb, 2, 2)).copy())


def test_the_static_mesh_loads_carry_the_input_torque_through_both_stages():
    """Each stage's normal load is the torque on its driver's shaft over r_b1 cos(beta_b)
    (the line of action is tangent to the base circle and inclined by beta_b in the flank):
    the input torque times the ratio of the stages before it. Round-off bound: the loads come
    out of a solve of the condensed system (condition ~1e7 with 1e9 N/m springs), 1e-9."""
    for helix in (0.0, 15.0):
        lay = two_stage(helix=helix)
        st = structure(lay)
        static(st)
        for m, mesh in enumerate(st.meshes):
            driver = lay.gear(lay.drivers[m][0])
            torque = 120.0 * (1.0 if driver.shaft == "a" else 40.0 / 20.0)
            pair = mesh.pair
            expected = torque / (pair.base_radius[0] * math.cos(pair.base_helix_angle))
            assert st.mesh_forces()[m] == pytest.approx(expected, rel=1e-9), (helix, m)


def test_every_shaft_is_in_static_equilibrium():
    """Per shaft, the forces on it sum to zero: its bearings' spring forces, its weight and
    the mesh forces on its gear nodes (each mesh element's force in the structure's frame),
    to round-off of the largest of them (1e-9 bound: sums of ~10 terms of a solve's
    output)."""
    lay = two_stage(helix=15.0, gravity=(3.0, -9.81))
    st = structure(lay)
    static(st)
    sys_ = st.system
    x = st.full_vector()
    nodes_force = np.zeros((sys_.n_nodes, DOF_PER_NODE))
    for w, ms in zip(st._work, st.mesh_states, strict=True):
        for k, node in enumerate(sys_.mesh_nodes[list(st._work).index(w)]):
            nodes_force[node] += ms.force[6 * k:6 * k + 6]
    for s, shaft in enumerate(lay.shafts):
        nodes = sys_.shaft_nodes[s]
        f = np.zeros(3)
        for b, spec in enumerate(lay.bearings):
            if spec.shaft == shaft.name:
                f[:2] -= STIFF * x[sys_.bearing_dofs[b]]
        f[:2] += lay.carried_mass(shaft.name) * np.array([3.0, -9.81])
        f += nodes_force[nodes, :3].sum(axis=0)
        thrust = min((b for b in lay.bearings if b.shaft == shaft.name), key=lambda b: b.position)
        node = sys_.bearing_nodes[lay.bearings.index(thrust)]
        f[2] -= shaft.axial_stiffness * x[dof(node, W)]
        scale = max(np.abs(nodes_force[nodes, :3]).max(), 1.0)
        assert np.abs(f).max() <= 1e-9 * scale, (shaft.name, f)
    # torque: the intermediate shaft's two meshes balance
    b_nodes = sys_.shaft_nodes[1]
    assert abs(nodes_force[b_nodes, THETA].sum()) <= 1e-9 * np.abs(
        nodes_force[b_nodes, THETA]).max()


def test_turning_a_stage_about_its_shaft_turns_its_forces_only():
    """The second stage's line of centres at 0 and 70 deg: the mesh loads are the same (the
    torque chain does not depend on the direction), to round-off."""
    loads = []
    for direction in (0.0, math.radians(70.0)):
        st = structure(two_stage(direction=direction))
        static(st)
        loads.append(st.mesh_forces())
    np.testing.assert_allclose(loads[0], loads[1], rtol=1e-12)


@pytest.mark.parametrize("hand, sign", [("left", -1.0), ("right", 1.0)])
def test_a_helical_driver_is_thrust_by_the_hand_rule(hand, sign):
    """A driver turning about +z is pushed along the thumb of the hand of its helix curled
    with the rotation (the textbook rule): a left-hand driver towards -z, a right-hand one
    towards +z; its thrust bearing carries F_n sin(beta_b). The axial reaction is read at the
    driver shaft's thrust spring (its first bearing); the shaft's weight does not act axially.
    Bound: 1e-9 of the thrust (round-off)."""
    other = {"left": "right", "right": "left"}[hand]
    lay = two_stage(helix=15.0, hands=(hand, other))
    st = structure(lay)
    static(st)
    sys_ = st.system
    node = sys_.bearing_nodes[0]  # a1: shaft a's first bearing
    reaction = -lay.shafts[0].axial_stiffness * st.full_vector()[dof(node, W)]
    pair = st.meshes[0].pair
    thrust = st.mesh_forces()[0] * math.sin(pair.base_helix_angle)
    assert -reaction == pytest.approx(sign * thrust, rel=1e-9)


def test_torsional_modes_with_stiff_supports_are_those_of_the_lumped_chain():
    """With rigid bearings next to the gears and light shafts the train's torsional modes
    are those of the lumped chain J_i theta_i'' + ... with the mean mesh stiffnesses along the
    lines of action (k_m = K[theta1, theta1] / (r_b1 cos beta_b)^2), the torsion of shaft b
    between its gears (G J / 60 mm) and of shaft c to its clamped end (G J / 50 mm), written
    here from the inertias and radii alone. The FE shafts are not rigid across (bending and
    shear between the supports add compliance in series with the mesh, of order
    k_m / k_lateral ~ 1 %: 0.9 % measured on the lowest mode); bound 3 %."""
    d = 0.2
    lay = two_stage(diameter=d, density=1.0, stiff_supports=True)
    st = structure(lay)
    rigid = 1e13
    kmesh = analyses.exact_mean_mesh_stiffness(st, rigid)
    modes = analyses.modes(st, rigid, mesh_stiffness=kmesh)
    fe = [f for f, k in zip(modes.frequency_hz, modes.kinetic_fraction, strict=True)
          if k[1] > 0.9][:4]
    rb = [r for m in st.meshes for r in m.pair.base_radius]
    k1, k2 = (analyses.line_of_action_stiffness(st, kmesh, m) for m in range(2))
    gj = 210e9 / (2.0 * 1.3) * math.pi * d**4 / 32.0
    k = np.zeros((4, 4))
    for v, stiffness in (([rb[0], rb[1], 0.0, 0.0], k1), ([0.0, 1.0, -1.0, 0.0], gj / 0.06),
                         ([0.0, 0.0, rb[2], rb[3]], k2), ([0.0, 0.0, 0.0, 1.0], gj / 0.05)):
        k += stiffness * np.outer(v, v)
    inertia = np.diag([g.polar_inertia for g in lay.gears])
    lumped = np.sqrt(scipy.linalg.eigh(k, inertia, eigvals_only=True)) / (2.0 * math.pi)
    np.testing.assert_allclose(fe, lumped, rtol=0.03)


def test_the_order_of_shafts_and_bearings_in_the_layout_does_not_matter():
    """The same train with its shafts and bearings listed in reverse order: other node and
    DOF numbers, the same physics. The static journal positions (by bearing name) and the
    mesh loads agree to round-off (1e-9: the solves' condition ~1e7 times eps)."""
    results = []
    for reverse in (False, True):
        lay = two_stage(helix=15.0, gravity=(0.0, -9.81), reverse=reverse)
        st = structure(lay)
        static(st)
        journals = dict(zip(lay.bearing_names, st.journal_states()[:, :2], strict=True))
        results.append((journals, st.mesh_forces()))
    (j0, f0), (j1, f1) = results
    scale = max(np.abs(v).max() for v in j0.values())
    for name, value in j0.items():
        np.testing.assert_allclose(j1[name], value, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(f1, f0, rtol=1e-9)


def test_newmark_keeps_order_two_on_two_stages():
    """The two-stage train (unbalance on the hub, a helical first stage, contact located at
    the events of both meshes, consistent start) over one period of the slower mesh with 64,
    128 and 256 steps per period of the faster one: the differences of successive runs fall
    by 2^p with p observed near 2 (>= 1.8 asserted; a first-order error, an event of one
    mesh not located or a wrong start, gives p near 1)."""
    lay = two_stage(helix=15.0)
    lay = Layout(lay.shafts, lay.gears, lay.meshes, lay.bearings, lay.drive,
                 (DiscSpec("hub", "a", 0.1, 0.8, 1e-3, 6e-4, unbalance=1e-4),))
    laws = (np.zeros((6, 2)), np.broadcast_to(STIFF * np.eye(2), (6, 2, 2)).copy(),
            np.broadcast_to(2e3 * np.eye(2), (6, 2, 2)).copy())
    ends = []
    for steps in (64, 128, 256):
        st = structure(lay, consistent_start=True, locate_contact=True, tol=1e-12)
        st.static(*laws[:2])
        st.set_damping_reference(STIFF)
        dt = st.mesh_period / steps
        slow = float(np.max(st.mesh_periods))
        for _ in range(round(slow / dt)):
            st.step(dt, *laws)
        ends.append(st.journal_states().ravel())
    d1 = np.linalg.norm(ends[0] - ends[1])
    d2 = np.linalg.norm(ends[1] - ends[2])
    assert math.log2(d1 / d2) >= 1.8, (d1, d2)

