"""The system description: a checked case (:mod:`fmu_src.case`) -> physics objects.

One place turns case fields (SI values) into the gear pair, the two-shaft structure, the mesh
element, the loads and the bearing models; the in-process master, ``gsb modal``, ``gsb run``
and the gear-shaft FMU all build their system here, so that they simulate the same thing. The
bearing FMUs' parameters of a case come from here too (:func:`bearing_parameters`). The gear
pair, the drivetrain and the damping model are built by :func:`fmu_src.case.gear_pair`,
:func:`~fmu_src.case.drivetrain` and :func:`~fmu_src.case.damping` (re-exported here), with
which the case loader checks those fields: a case that loads is a case that builds.

Bearings: 1, 2 on the pinion shaft (turning about +z), 3, 4 on the gear shaft (turning about -z,
mirrored local frame, :mod:`bearing_fmu.frames`); local x along s. Shaft speeds: omega and
omega z1 / z2 (:func:`gear_fmu.loads.shaft_speeds`).
"""

from __future__ import annotations

import math

from bearing_fmu import BearingData, BearingModel, model_class
from bearing_fmu.frames import LocalFrame
from fmu_src.case import Case, damping, drivetrain, gear_pair, model_option_fields
from gear_fmu.loads import StructureLoads, shaft_speeds
from gear_fmu.mesh.element import MeshElement
from gear_fmu.mesh.geometry import GearPair
from gear_fmu.structure import Structure
from gear_fmu.system import GearBody, GearShaftSystem, Shaft
from gear_fmu.timoshenko import HollowSection

__all__ = [
    "BEARING_FRAMES",
    "bearing_data",
    "bearing_models",
    "bearing_options",
    "bearing_parameters",
    "bearing_speeds",
    "damping",
    "drivetrain",
    "gear_pair",
    "gear_shaft_system",
    "mesh_element",
    "mesh_period",
    "structure",
    "structure_loads",
    "time_step",
]

#: local frame of bearings 1-4 in the global (s, t) plane
BEARING_FRAMES = (LocalFrame(0.0, 1), LocalFrame(0.0, 1), LocalFrame(0.0, -1),
                  LocalFrame(0.0, -1))


def gear_shaft_system(case: Case, pair: GearPair | None = None) -> GearShaftSystem:
    """Table 2 shafts and Table 1 gear bodies -> :class:`gear_fmu.system.GearShaftSystem`."""
    pair = gear_pair(case) if pair is None else pair
    material = dict(young=case["shafts.young_modulus"], poisson=case["shafts.poisson_ratio"],
                    density=case["shafts.density"])
    shafts = tuple(
        Shaft(HollowSection(do, di, **material), case["shafts.length"], case["shafts.elements"])
        for do, di in zip(case["shafts.outer_diameter"], case["shafts.inner_diameter"],
                          strict=True))
    gears = tuple(GearBody(m, r, b, case["shafts.density"], ip, idiam)
                  for m, r, b, ip, idiam in zip(
                      case["gear_pair.mass"], pair.pitch_radius, pair.face_width,
                      case["gear_pair.polar_inertia"], case["gear_pair.diametral_inertia"],
                      strict=True))
    return GearShaftSystem(shafts=shafts, gears=gears,  # type: ignore[arg-type]
                           centre_distance=pair.centre_distance, teeth=pair.teeth,
                           helix_angle_deg=math.degrees(pair.helix_angle),
                           drivetrain=drivetrain(case))


def structure_loads(case: Case) -> StructureLoads:
    """Operating point (Sec. 4.1) -> :class:`gear_fmu.loads.StructureLoads`."""
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
    [N/m] or (4, 2, 2); :meth:`gear_fmu.structure.Structure.set_damping_reference` replaces it
    once the static bearing stiffness is known.
    """
    pair = gear_pair(case)
    return Structure(gear_shaft_system(case, pair), mesh_element(case, pair),
                     structure_loads(case), zeta=damping(case),
                     damping_bearing_stiffness=damping_bearing_stiffness,
                     tol=case["simulation.tolerance"],
                     consistent_start=case["simulation.consistent_start"],
                     locate_contact=case["simulation.locate_contact"])


def mesh_period(case: Case) -> float:
    """Mesh period 2 pi / (omega z1) of the case [s]."""
    return 2.0 * math.pi / (case["operation.speed"] * case["gear_pair.teeth"][0])


def time_step(case: Case) -> float:
    """Time step of the case: the mesh period / ``simulation.steps_per_mesh_period`` [s]."""
    return mesh_period(case) / case["simulation.steps_per_mesh_period"]


def bearing_data(case: Case) -> list[BearingData]:
    """Table 3 -> one :class:`bearing_fmu.base.BearingData` per bearing."""
    return [BearingData(case["bearings.diameter"][i], case["bearings.length"][i],
                        case["bearings.clearance"][i], case["bearings.viscosity"][i])
            for i in range(4)]


def bearing_speeds(case: Case) -> list[float]:
    """Shaft speed magnitude at bearings 1-4 [rad/s]."""
    w1, w2 = shaft_speeds(structure_loads(case), case["gear_pair.teeth"])
    return [w1, w1, w2, w2]


def bearing_options(case: Case) -> dict:
    """The case's settings of its bearing model (``bearings.model``): ``{option key: value}``
    (the model's declared :attr:`~bearing_fmu.base.BearingModel.options`)."""
    return {o.key: case[f"bearings.{o.key}"]
            for o in model_class(case["bearings.model"]).options}


def bearing_models(case: Case) -> list[BearingModel]:
    """In-process bearing models of the case (``bearings.model``), each built by the
    registry's ``from_parameters`` with the case's options."""
    cls = model_class(case["bearings.model"])
    options = bearing_options(case)
    return [cls.from_parameters(data, **options) for data in bearing_data(case)]


def bearing_parameters(case: Case) -> list[dict]:
    """Parameters of the four bearing FMUs of a case (:func:`fmu_src.contract.bearing_variables`:
    geometry, lubricant, frame, and every model option, so one list serves every model)."""
    option_keys = [f.key.split(".", 1)[1] for f in model_option_fields()]
    out = []
    for data, frame in zip(bearing_data(case), BEARING_FRAMES, strict=True):
        params = dict(D=data.diameter, L=data.length, C=data.clearance, mu=data.viscosity,
                      frame_angle=frame.angle, rotation_sign=frame.rotation_sign)
        params.update({k: case[f"bearings.{k}"] for k in option_keys})
        out.append(params)
    return out
