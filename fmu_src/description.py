"""The system description: a checked case (:mod:`fmu_src.case`) -> physics objects.

One place turns a case into the gear train (:func:`layout`, :class:`gear_fmu.layout.Layout`,
the single source of its topology) and the train into the gear pairs, the structure, the mesh
elements, the loads and the bearing models; the in-process master, ``gsb modal``, ``gsb run``
and the gear-shaft FMU all build their system here, so that they simulate the same thing. The
bearing FMUs' parameters of a case come from here too (:func:`bearing_parameters`). The
layout, the gear pairs, the drivetrain and the damping model are built by
:mod:`fmu_src.train`, with which the case loader checks a case: a case that loads is a case
that builds.

Bearings: each in the frame of its shaft (local x along s, mirrored when the shaft turns about
-z, :mod:`bearing_fmu.frames`), at its shaft's speed (:attr:`gear_fmu.layout.Layout.speeds`),
each of its own model.
"""

from __future__ import annotations

import math

from bearing_fmu import BearingData, BearingModel, model_class
from bearing_fmu.frames import LocalFrame
from fmu_src import train
from fmu_src.case import Case, CaseError, model_option_fields
from fmu_src.units import parse_speed_profile
from gear_fmu.layout import Layout, LayoutError
from gear_fmu.loads import StructureLoads
from gear_fmu.mesh.element import MeshElement
from gear_fmu.mesh.geometry import GearGeometryError, GearPair
from gear_fmu.mesh.train import mesh_elements
from gear_fmu.speed_profile import SpeedProfile
from gear_fmu.structure import Structure
from gear_fmu.system import GearShaftSystem

__all__ = [
    "bearing_data",
    "bearing_frames",
    "bearing_models",
    "bearing_options",
    "bearing_parameters",
    "bearing_speeds",
    "damping",
    "drivetrain",
    "gear_pairs",
    "gear_shaft_system",
    "layout",
    "mesh_elements_of",
    "mesh_period",
    "mesh_teeth",
    "shared_bearing_model",
    "speed_profile",
    "structure",
    "structure_loads",
    "time_step",
]


def _named(case: Case, build, *args):
    """``build(case, *args)``, its errors as :class:`~fmu_src.fields.CaseError` naming the
    case's file."""
    try:
        return build(case, *args)
    except (LayoutError, GearGeometryError, ValueError) as exc:
        if isinstance(exc, CaseError):
            raise
        raise CaseError(f"{case.source}: {exc}") from None


def layout(case: Case) -> Layout:
    """The gear train of a case (:func:`fmu_src.train.layout`); an error names the file."""
    return _named(case, train.layout)


def gear_pairs(case: Case) -> tuple[GearPair, ...]:
    """One :class:`gear_fmu.mesh.geometry.GearPair` per mesh, in the layout's order, the
    driver first (:func:`fmu_src.train.gear_pairs`)."""
    return _named(case, train.gear_pairs)


def drivetrain(case: Case):
    """The case's :class:`gear_fmu.drivetrain.Drivetrain` (:func:`fmu_src.train.drivetrain`)."""
    return _named(case, train.drivetrain)


def damping(case: Case):
    """The case's :class:`gear_fmu.modal.damping.DampingModel`
    (:func:`fmu_src.train.damping`)."""
    return _named(case, train.damping)


def gear_shaft_system(case: Case) -> GearShaftSystem:
    """The shafts, gear bodies and discs of the case ->
    :class:`gear_fmu.system.GearShaftSystem`."""
    return GearShaftSystem(layout(case))


def structure_loads(case: Case) -> StructureLoads:
    """The drive (Sec. 4.1) -> :class:`gear_fmu.loads.StructureLoads` (the unbalances are
    the layout's, :class:`gear_fmu.system.Unbalances`)."""
    d = layout(case).drive
    gravity = tuple(d.gravity)
    profile = speed_profile(case)
    return StructureLoads(torque=d.torque, input_speed=d.speed,
                          gravity=gravity if any(gravity) else None,
                          profile=profile if profile.varies else None)


def speed_profile(case: Case) -> SpeedProfile:
    """The input speed against time: ``drive.speed``, ramped or following a table as
    ``drive.speed_profile`` says (:func:`fmu_src.units.parse_speed_profile`; constant when it
    is empty; a table starts at ``drive.speed``: :func:`fmu_src.case.parse_case` checks it)."""
    w0 = float(layout(case).drive.speed)
    given = parse_speed_profile(case["drive.speed_profile"])
    if given is None:
        return SpeedProfile.ramp(w0, w0)
    kind, data = given
    if kind == "ramp":
        w1, duration, start = data
        return SpeedProfile.ramp(w0, w1, start, duration)
    return SpeedProfile(tuple(t for t, _ in data), tuple(w for _, w in data))


def mesh_elements_of(case: Case) -> tuple[MeshElement, ...]:
    """The distributed mesh element of every mesh, each in its pair's own frame
    (:func:`gear_fmu.mesh.train.mesh_elements`)."""
    lay = layout(case)
    return mesh_elements(lay, gear_pairs(case))


def structure(case: Case, damping_bearing_stiffness=1e8) -> Structure:
    """The gear-shaft structure of the case (Newmark step, static solve, modes).

    ``damping_bearing_stiffness``: reference bearing stiffness of the modal damping
    [N/m] or (nb, 2, 2); :meth:`gear_fmu.structure.Structure.set_damping_reference` replaces
    it once the static bearing stiffness is known.
    """
    lay = layout(case)
    return Structure(GearShaftSystem(lay), mesh_elements(lay, gear_pairs(case)),
                     structure_loads(case), zeta=damping(case),
                     damping_bearing_stiffness=damping_bearing_stiffness,
                     tol=case["simulation.tolerance"],
                     consistent_start=case["simulation.consistent_start"],
                     locate_contact=case["simulation.locate_contact"],
                     gyroscopic=case["simulation.gyroscopic"])


def mesh_period(case: Case) -> float:
    """Mesh period of the fastest mesh, ``2 pi / (|omega_driver| z_driver)`` [s], at the
    highest input speed of the run (:func:`speed_profile`: a run-up's final speed)."""
    lay = layout(case)
    top = speed_profile(case).max_speed / float(lay.drive.speed)
    frequency = max(abs(float(lay.speeds[lay.shaft_index[lay.gear(d).shaft]]))
                    * lay.gear(d).teeth for d, _ in lay.drivers)
    return 2.0 * math.pi / (frequency * top)


def mesh_teeth(case: Case) -> list[tuple[int, int]]:
    """The teeth of each mesh's gears, driver first, in the layout's order."""
    lay = layout(case)
    return [(lay.gear(d).teeth, lay.gear(n).teeth) for d, n in lay.drivers]


def time_step(case: Case) -> float:
    """Time step of the case: the fastest mesh's period / ``simulation.steps_per_mesh_period``
    [s]."""
    return mesh_period(case) / case["simulation.steps_per_mesh_period"]


def bearing_data(case: Case) -> list[BearingData]:
    """One :class:`bearing_fmu.base.BearingData` per bearing (Table 3), in the case's order."""
    return [BearingData(*(case[f"bearings.{name}.{k}"]
                          for k in ("diameter", "length", "clearance", "viscosity")))
            for name in case.names("bearings")]


def bearing_speeds(case: Case) -> list[float]:
    """Speed magnitude of each bearing's shaft [rad/s], in the case's bearing order."""
    lay = layout(case)
    return [abs(float(lay.speeds[lay.shaft_index[b.shaft]])) for b in lay.bearings]


def bearing_frames(case: Case | Layout) -> list[LocalFrame]:
    """The local frame of each bearing (its x axis along s; mirrored on a shaft turning about
    -z, :mod:`bearing_fmu.frames`), in the case's bearing order."""
    lay = case if isinstance(case, Layout) else layout(case)
    return [LocalFrame(0.0, int(lay.directions[lay.shaft_index[b.shaft]]))
            for b in lay.bearings]


def shared_bearing_model(case: Case) -> str | None:
    """The model every bearing of the case has (``"hybrid"``), None when they differ."""
    models = {case[f"bearings.{name}.model"] for name in case.names("bearings")}
    return models.pop() if len(models) == 1 else None


def bearing_options(case: Case, bearing: str) -> dict:
    """The settings of bearing ``bearing``'s model: ``{option key: value}`` (the model's
    declared :attr:`~bearing_fmu.base.BearingModel.options`)."""
    model = case[f"bearings.{bearing}.model"]
    return {o.key: case[f"bearings.{bearing}.{o.key}"] for o in model_class(model).options}


def bearing_models(case: Case) -> list[BearingModel]:
    """In-process bearing models of the case, each of its own ``model``, built by the
    registry's ``from_parameters`` with its options."""
    return [model_class(case[f"bearings.{name}.model"]).from_parameters(
                data, **bearing_options(case, name))
            for name, data in zip(case.names("bearings"), bearing_data(case), strict=True)]


def bearing_parameters(case: Case) -> list[dict]:
    """Parameters of the bearing FMUs of a case, one dict per bearing
    (:func:`fmu_src.contract.bearing_variables`: geometry, lubricant, frame, and every model
    option, so one list serves every model)."""
    option_keys = [f.name for f in model_option_fields()]
    out = []
    for name, data, frame in zip(case.names("bearings"), bearing_data(case),
                                 bearing_frames(case), strict=True):
        params = dict(D=data.diameter, L=data.length, C=data.clearance, mu=data.viscosity,
                      frame_angle=frame.angle, rotation_sign=frame.rotation_sign)
        params.update({k: case[f"bearings.{name}.{k}"] for k in option_keys})
        out.append(params)
    return out
