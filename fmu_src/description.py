"""The system description: a checked case (:mod:`fmu_src.case`) -> physics objects.

One place turns a case into the train's layout (:func:`layout`, :class:`gear_fmu.layout
.Layout`, the single source of its topology) and the layout into the structure, its mesh
elements, the loads and the bearing models; the in-process master, ``gsb modal``, ``gsb run``
and the gear-shaft FMU all build their system here, so that they simulate the same thing. The
bearing FMUs' parameters of a case come from here too (:func:`bearing_parameters`). The
drivetrain and the damping model are built by :func:`fmu_src.case.drivetrain` and
:func:`~fmu_src.case.damping` (re-exported here), with which the case loader checks those
fields: a case that loads is a case that builds.

Bearings: each in the frame of its shaft (local x along s, mirrored when the shaft turns about
-z, :mod:`bearing_fmu.frames`), at its shaft's speed (:attr:`gear_fmu.layout.Layout.speeds`).
"""

from __future__ import annotations

import math

from bearing_fmu import BearingData, BearingModel, model_class
from bearing_fmu.frames import LocalFrame
from fmu_src.case import Case, damping, drivetrain, layout
from gear_fmu.layout import Layout
from gear_fmu.loads import StructureLoads
from gear_fmu.mesh.element import MeshElement
from gear_fmu.mesh.geometry import GearPair
from gear_fmu.mesh.train import gear_pair, mesh_elements
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
    "structure",
    "structure_loads",
    "time_step",
]


def gear_pairs(case: Case | Layout) -> list[GearPair]:
    """One gear pair per mesh of the case (:func:`gear_fmu.mesh.train.gear_pair`)."""
    lay = case if isinstance(case, Layout) else layout(case)
    return [gear_pair(lay, m) for m in range(len(lay.meshes))]


def gear_shaft_system(case: Case) -> GearShaftSystem:
    """The shafts, gear bodies and discs of the case -> :class:`gear_fmu.system
    .GearShaftSystem`."""
    return GearShaftSystem(layout(case))


def structure_loads(case: Case) -> StructureLoads:
    """The drive (Sec. 4.1) -> :class:`gear_fmu.loads.StructureLoads`."""
    d = layout(case).drive
    gravity = tuple(d.gravity) if any(d.gravity) else None
    return StructureLoads(torque=d.torque, input_speed=d.speed, gravity=gravity)


def mesh_elements_of(case: Case) -> tuple[MeshElement, ...]:
    """The distributed mesh element of every mesh, each in its pair's own frame
    (:func:`gear_fmu.mesh.train.mesh_elements`)."""
    return mesh_elements(layout(case))


def structure(case: Case, damping_bearing_stiffness=1e8) -> Structure:
    """The gear-shaft structure of the case (Newmark step, static solve, modes).

    ``damping_bearing_stiffness``: reference bearing stiffness of the modal damping
    [N/m] or (nb, 2, 2); :meth:`gear_fmu.structure.Structure.set_damping_reference` replaces
    it once the static bearing stiffness is known.
    """
    lay = layout(case)
    return Structure(GearShaftSystem(lay), mesh_elements(lay), structure_loads(case),
                     zeta=damping(case), damping_bearing_stiffness=damping_bearing_stiffness,
                     tol=case["simulation.tolerance"],
                     consistent_start=case["simulation.consistent_start"],
                     locate_contact=case["simulation.locate_contact"])


def mesh_period(case: Case) -> float:
    """The shortest mesh period of the case, ``2 pi / (omega_driver z_driver)`` [s]."""
    lay = layout(case)
    periods = []
    for driver, _ in lay.drivers:
        g = lay.gear(driver)
        w = abs(float(lay.speeds[lay.shaft_index[g.shaft]]))
        periods.append(2.0 * math.pi / (w * g.teeth) if w > 0.0 else math.inf)
    return min(periods)


def time_step(case: Case) -> float:
    """Time step of the case: the shortest mesh period / ``simulation.steps_per_mesh_period``
    [s]."""
    return mesh_period(case) / case["simulation.steps_per_mesh_period"]


def bearing_data(case: Case) -> list[BearingData]:
    """Each bearing's geometry and lubricant (Table 3), the layout's order."""
    return [BearingData(b.diameter, b.length, b.clearance, b.viscosity)
            for b in layout(case).bearings]


def bearing_frames(case: Case | Layout) -> list[LocalFrame]:
    """Each bearing's local frame in the global (s, t) plane: x along s, mirrored when its
    shaft turns about -z."""
    lay = case if isinstance(case, Layout) else layout(case)
    return [LocalFrame(0.0, int(lay.directions[lay.shaft_index[b.shaft]]))
            for b in lay.bearings]


def bearing_speeds(case: Case) -> list[float]:
    """Shaft speed magnitude at each bearing [rad/s]."""
    lay = layout(case)
    return [abs(float(lay.speeds[lay.shaft_index[b.shaft]])) for b in lay.bearings]


def bearing_options(case: Case, bearing: int = 0) -> dict:
    """The settings of a bearing's model: ``{option key: value}`` (the model's declared
    :attr:`~bearing_fmu.base.BearingModel.options`)."""
    b = layout(case).bearings[bearing]
    options = b.option_dict
    return {o.key: options[o.key] for o in model_class(b.model).options}


def bearing_models(case: Case) -> list[BearingModel]:
    """In-process bearing models of the case, each bearing its own model, built by the
    registry's ``from_parameters`` with its options."""
    lay = layout(case)
    out = []
    for i, (b, data) in enumerate(zip(lay.bearings, bearing_data(case), strict=True)):
        out.append(model_class(b.model).from_parameters(data, **bearing_options(case, i)))
    return out


def bearing_parameters(case: Case) -> list[dict]:
    """Parameters of the bearing FMUs of a case (:func:`fmu_src.contract.bearing_variables`:
    geometry, lubricant, frame, and every option of its model)."""
    lay = layout(case)
    out = []
    for b, frame in zip(lay.bearings, bearing_frames(lay), strict=True):
        params = dict(D=b.diameter, L=b.length, C=b.clearance, mu=b.viscosity,
                      frame_angle=frame.angle, rotation_sign=frame.rotation_sign)
        params.update(b.option_dict)
        out.append(params)
    return out
