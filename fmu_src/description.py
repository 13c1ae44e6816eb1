"""The system description: a checked case (:mod:`fmu_src.case`) -> physics objects.

One place turns case fields (SI values) into the gear pair, the two-shaft structure, the mesh
element, the loads and the bearing models; the in-process master, ``gsb modal``, ``gsb run``
and the gear-shaft FMU all build their system here, so that they simulate the same thing. The
bearing FMUs' parameters of a case come from here too (:func:`bearing_parameters`).

Bearings: 1, 2 on the pinion shaft (turning about +z), 3, 4 on the gear shaft (turning about -z,
mirrored local frame, :mod:`bearing_fmu.frames`); local x along s. Shaft speeds: omega and
omega z1 / z2 (:func:`gear_fmu.loads.shaft_speeds`).
"""

from __future__ import annotations

import math
from dataclasses import fields

from bearing_fmu import BearingData, BearingModel, model_class
from bearing_fmu.frames import LocalFrame
from fmu_src.case import Case
from gear_fmu.damping import DampingModel
from gear_fmu.drivetrain import Drivetrain
from gear_fmu.geometry import GearPair
from gear_fmu.loads import StructureLoads, shaft_speeds
from gear_fmu.mesh import MeshElement
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
    gears = tuple(GearBody(m, r, b, case["shafts.density"], ip, idiam)
                  for m, r, b, ip, idiam in zip(
                      case["gear_pair.mass"], pair.pitch_radius, pair.face_width,
                      case["gear_pair.polar_inertia"], case["gear_pair.diametral_inertia"],
                      strict=True))
    return GearShaftSystem(shafts=shafts, gears=gears,  # type: ignore[arg-type]
                           centre_distance=pair.centre_distance, teeth=pair.teeth,
                           helix_angle_deg=math.degrees(pair.helix_angle),
                           drivetrain=drivetrain(case))


def drivetrain(case) -> Drivetrain:
    """``drivetrain.*`` fields -> :class:`gear_fmu.drivetrain.Drivetrain` (a Case or its
    values; one field per attribute, same name); its errors name the fields."""
    return Drivetrain(**{f.name: case[f"drivetrain.{f.name}"] for f in fields(Drivetrain)})


def damping(case) -> DampingModel:
    """``simulation.damping_*``, ``rayleigh_*``, ``mesh_damping*`` fields ->
    :class:`gear_fmu.damping.DampingModel` (a Case or its values)."""
    try:
        return DampingModel(
            kind=case["simulation.damping_model"], ratio=case["simulation.damping_ratio"],
            basis=case["simulation.damping_basis"],
            rayleigh_frequencies=tuple(case["simulation.rayleigh_frequencies"]),
            rayleigh_alpha=case["simulation.rayleigh_alpha"],
            rayleigh_beta=case["simulation.rayleigh_beta"],
            mesh_ratio=case["simulation.mesh_damping_ratio"],
            mesh_coefficient=case["simulation.mesh_damping"])
    except ValueError as exc:
        raise ValueError(f"simulation damping fields: {exc}") from None


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
    """Parameters of the four bearing FMUs of a case (:data:`fmu_src.contract.BEARING_VARIABLES`:
    geometry, lubricant, frame, and every model option, so one list serves every model)."""
    from fmu_src.contract import bearing_option_keys

    out = []
    for data, frame in zip(bearing_data(case), BEARING_FRAMES, strict=True):
        params = dict(D=data.diameter, L=data.length, C=data.clearance, mu=data.viscosity,
                      frame_angle=frame.angle, rotation_sign=frame.rotation_sign)
        params.update({k: case[f"bearings.{k}"] for k in bearing_option_keys()})
        out.append(params)
    return out
