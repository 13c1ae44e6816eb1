"""The gear pairs and mesh elements of a gear train (:class:`gear_fmu.layout.Layout`).

Each mesh of a layout becomes a :class:`~gear_fmu.mesh.geometry.GearPair` (driver first, the
driver being the gear nearer the input: :attr:`gear_fmu.layout.Layout.drivers`) and a
:class:`~gear_fmu.mesh.element.MeshElement` working in the pair's own frame
(:func:`~gear_fmu.mesh.element.pair_frame`): the line of centres from the driver's shaft to
the driven one's, mirrored across it when the driver turns about -z, and mirrored in z when the
driver is right-handed (the element's own pinion is left-handed). The teeth take the material
of the driver's shaft.
"""

from __future__ import annotations

import math

import numpy as np

from gear_fmu.layout import Layout
from gear_fmu.mesh.element import MeshElement, ToothDeviations, pair_frame
from gear_fmu.mesh.geometry import GearPair

__all__ = ["gear_pair", "mesh_element", "mesh_elements", "mesh_frame"]

def gear_pair(layout: Layout, m: int) -> GearPair:
    """The gear pair of mesh ``m``, driver first (module docstring; the layout checked that
    its gears can be a pair); a :class:`~gear_fmu.mesh.geometry.GearGeometryError` when they
    do not mesh at the centre distance."""
    mesh = layout.meshes[m]
    driver, driven = (layout.gear(g) for g in layout.drivers[m])
    material = layout.shaft(driver.shaft)
    return GearPair(
        teeth=(driver.teeth, driven.teeth), module=driver.module,
        pressure_angle=driver.pressure_angle, centre_distance=mesh.centre_distance,
        face_width=(driver.face_width, driven.face_width), helix_angle=driver.helix_angle,
        profile_shift=(driver.profile_shift, driven.profile_shift),
        addendum_coefficient=driver.addendum_coefficient,
        dedendum_coefficient=driver.dedendum_coefficient, young=material.young,
        poisson=material.poisson)


def _frame_parts(layout: Layout, m: int) -> tuple[float, int, bool]:
    """``(direction [rad], turn sign, flip hand)`` of mesh m's own frame (module
    docstring)."""
    mesh = layout.meshes[m]
    driver = layout.gear(layout.drivers[m][0])
    direction = mesh.direction if mesh.gears[0] == driver.name else mesh.direction + math.pi
    turn = int(layout.directions[layout.shaft_index[driver.shaft]])
    mirrored_hand = {"right": "left", "left": "right", "": ""}[driver.hand] if turn < 0 \
        else driver.hand
    return direction, turn, mirrored_hand == "right"


def mesh_frame(layout: Layout, m: int) -> np.ndarray | None:
    """``T`` (12, 12) of mesh m's own frame (:func:`gear_fmu.mesh.element.pair_frame`), None
    where it is the structure's (the paper's pair)."""
    direction, turn, flip = _frame_parts(layout, m)
    if direction == 0.0 and turn > 0 and not flip:
        return None
    return pair_frame(direction, turn, flip)


def mesh_element(layout: Layout, m: int, pair: GearPair | None = None,
                 n_table: int = 129) -> MeshElement:
    """The mesh element of mesh ``m`` in its own frame, its contact term linearised at the
    nominal line load of the torque its driver's shaft carries
    (:meth:`gear_fmu.layout.Layout.torque_on`, at least 1 N m)."""
    pair = gear_pair(layout, m) if pair is None else pair
    mesh = layout.meshes[m]
    driver, driven = (layout.gear(g) for g in layout.drivers[m])
    direction, turn, flip = _frame_parts(layout, m)
    z = [layout.shaft(g.shaft).offset + g.position for g in (driver, driven)]
    centre = z[0] if driver.face_width <= driven.face_width else z[1]
    node_z = [zi - centre for zi in z]
    lead = mesh.lead_slope
    if flip:
        node_z = [-zi for zi in node_z]
        lead = -lead
    sigma = 1.0 if turn > 0 else -1.0
    deviations = ToothDeviations(
        tip_relief=(driver.tip_relief, driven.tip_relief),
        relief_length=(driver.relief_length, driven.relief_length),
        relief_exponent=mesh.relief_exponent, crowning=mesh.crowning, lead_slope=lead,
        pitch_errors=(tuple(driver.pitch_errors), tuple(driven.pitch_errors)),
        runout=(driver.runout, driven.runout),
        runout_phase=tuple(sigma * (g.runout_phase - direction) if g.runout else 0.0
                           for g in (driver, driven)))
    torque = max(layout.torque_on(driver.shaft), 1.0)
    return MeshElement(pair, pair.nominal_line_load(torque), n_slices=mesh.slices,
                       deviations=deviations, gear_node_z=tuple(node_z), n_table=n_table,
                       frame=mesh_frame(layout, m))


def mesh_elements(layout: Layout, pairs=None) -> tuple[MeshElement, ...]:
    """One :func:`mesh_element` per mesh of the layout, in its order (``pairs``: their gear
    pairs when already built)."""
    pairs = pairs or [None] * len(layout.meshes)
    return tuple(mesh_element(layout, m, pair) for m, pair in enumerate(pairs))
