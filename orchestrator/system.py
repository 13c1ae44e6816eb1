"""The system description: a checked case (:mod:`orchestrator.case`) -> physics objects.

One place turns case fields (SI values) into the gear pair, the two-shaft structure, the mesh
element, the loads and the bearing models; the in-process master, ``gsb modal``, ``gsb run`` and
the gear-shaft FMU all build their system here, so that they simulate the same thing.

Bearings: 1, 2 on the pinion shaft (turning about +z), 3, 4 on the gear shaft (turning about -z,
mirrored local frame, :mod:`bearing_fmu.frames`); local x along s. Shaft speeds: omega and
omega z1 / z2.
"""

from __future__ import annotations

import math

from bearing_fmu import BearingData, model_class
from bearing_fmu.frames import LocalFrame
from gear_fmu.geometry import GearPair
from gear_fmu.mesh import MeshElement
from gear_fmu.structure import Structure, StructureLoads
from gear_fmu.system import GearBody, GearShaftSystem, Shaft
from gear_fmu.timoshenko import HollowSection
from orchestrator.case import Case

__all__ = [
    "BEARING_FRAMES",
    "bearing_data",
    "bearing_models",
    "bearing_speeds",
    "gear_pair",
    "gear_shaft_system",
    "linearised",
    "mesh_element",
    "structure",
    "structure_loads",
]

#: local frame of bearings 1-4 in the global (s, t) plane
BEARING_FRAMES = (LocalFrame(0.0, 1), LocalFrame(0.0, 1), LocalFrame(0.0, -1),
                  LocalFrame(0.0, -1))


def gear_pair(case: Case) -> GearPair:
    """Table 1 fields -> :class:`gear_fmu.geometry.GearPair` (checked geometry)."""
    return GearPair(
        teeth=tuple(case["gear_pair.teeth"]),
        module=case["gear_pair.module"],
        pressure_angle=case["gear_pair.pressure_angle"],
        centre_distance=case["gear_pair.centre_distance"],
        face_width=tuple(case["gear_pair.face_width"]),
        helix_angle=case["gear_pair.helix_angle"],
        profile_shift=tuple(case["gear_pair.profile_shift"]),
        addendum_coefficient=case["gear_pair.addendum_coefficient"],
        dedendum_coefficient=case["gear_pair.dedendum_coefficient"],
        young=case["shafts.young_modulus"],
        poisson=case["shafts.poisson_ratio"],
    )


def gear_shaft_system(case: Case, pair: GearPair | None = None) -> GearShaftSystem:
    """Table 2 shafts and Table 1 gear bodies -> :class:`gear_fmu.system.GearShaftSystem`."""
    pair = gear_pair(case) if pair is None else pair
    material = dict(young=case["shafts.young_modulus"], poisson=case["shafts.poisson_ratio"],
                    density=case["shafts.density"])
    shafts = tuple(
        Shaft(HollowSection(do, di, **material), case["shafts.length"], case["shafts.elements"])
        for do, di in zip(case["shafts.outer_diameter"], case["shafts.inner_diameter"],
                          strict=True))
    gears = tuple(GearBody(m, r, b, case["shafts.density"]) for m, r, b in zip(
        case["gear_pair.mass"], pair.pitch_radius, pair.face_width, strict=True))
    return GearShaftSystem(shafts=shafts, gears=gears,  # type: ignore[arg-type]
                           centre_distance=pair.centre_distance, teeth=pair.teeth,
                           helix_angle_deg=math.degrees(pair.helix_angle))


def structure_loads(case: Case) -> StructureLoads:
    """Operating point (Sec. 4.1) -> :class:`gear_fmu.structure.StructureLoads`."""
    return StructureLoads(
        torque=case["operation.torque"], input_speed=case["operation.speed"],
        unbalance=tuple(case["operation.unbalance"]),
        gravity=(0.0, -9.81) if case["operation.gravity"] else None)


def mesh_element(case: Case, pair: GearPair | None = None) -> MeshElement:
    """The distributed mesh element, contact term linearised at the nominal line load."""
    pair = gear_pair(case) if pair is None else pair
    return MeshElement(pair, pair.nominal_line_load(max(case["operation.torque"], 1.0)))


def structure(case: Case, damping_bearing_stiffness=1e8) -> Structure:
    """The gear-shaft structure of the case (Newmark step, static solve, modes).

    ``damping_bearing_stiffness``: reference bearing stiffness of the modal damping
    [N/m] or (4, 2, 2); :meth:`Structure.set_damping_reference` replaces it once the static
    bearing stiffness is known.
    """
    pair = gear_pair(case)
    return Structure(gear_shaft_system(case, pair), mesh_element(case, pair),
                     structure_loads(case), zeta=case["simulation.damping_ratio"],
                     damping_bearing_stiffness=damping_bearing_stiffness,
                     tol=case["simulation.tolerance"])


def bearing_data(case: Case) -> list[BearingData]:
    """Table 3 -> one :class:`bearing_fmu.BearingData` per bearing."""
    return [BearingData(case["bearings.diameter"][i], case["bearings.length"][i],
                        case["bearings.clearance"][i], case["bearings.viscosity"][i])
            for i in range(4)]


def bearing_speeds(case: Case) -> list[float]:
    """Shaft speed magnitude at bearings 1-4 [rad/s]."""
    z1, z2 = case["gear_pair.teeth"]
    w = case["operation.speed"]
    return [w, w, w * z1 / z2, w * z1 / z2]


def bearing_models(case: Case, model: str | None = None) -> list:
    """In-process bearing models of the case (``model`` overrides ``bearings.model``).

    For ``linear`` the hybrid models are returned: the 8 coefficients are frozen from them at
    the static solution X0 (paper Sec. 3.3.1, Table 4 case 0), see :func:`linearised`.
    """
    name = case["bearings.model"] if model is None else model
    out = []
    for data in bearing_data(case):
        if name in ("hybrid", "linear"):
            out.append(model_class("hybrid")(data, n=case["bearings.nodes"]))
        elif name == "fd":
            out.append(model_class("fd")(data, n_theta=case["bearings.nodes"],
                                         n_xi=case["bearings.axial_intervals"]))
        elif name == "short":
            out.append(model_class("short")(data))
        elif name == "lumped":
            out.append(model_class("lumped")(data, stiffness=case["bearings.lumped_stiffness"],
                                             damping=case["bearings.lumped_damping"]))
        else:
            raise ValueError(f"unknown bearing model {name!r}")
    return out


def linearised(models, journal_states, speeds) -> list:
    """Linear 8-coefficient bearings (Eq. 17-18) frozen at the static journal positions.

    ``journal_states`` (4, 4) global [s, t, s_dot, t_dot] at X0, ``speeds`` [rad/s]
    (:func:`bearing_speeds`); frames :data:`BEARING_FRAMES`.
    """
    from bearing_fmu.linear import LinearBearing

    out = []
    for model, frame, state, omega in zip(models, BEARING_FRAMES, journal_states,
                                          speeds, strict=True):
        x0, y0 = frame.to_local(state[:2])
        out.append(LinearBearing.linearise(model, x0, y0, omega))
    return out
