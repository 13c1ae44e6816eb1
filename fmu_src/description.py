"""The system description: a checked case (:mod:`fmu_src.case`) -> physics objects.

One place turns a case into the gear train (:func:`layout`, :class:`gear_fmu.layout.Layout`)
and the train into the gear pairs, the structure, the mesh elements, the loads and the bearing
models; the in-process master, ``gsb modal``, ``gsb run`` and the gear-shaft FMU all build their
system here, so that they simulate the same thing. The bearing FMUs' parameters of a case come
from here too (:func:`bearing_parameters`). The layout, the gear pairs, the drivetrain and the
damping model are built by :mod:`fmu_src.train`, with which the case loader checks a case: a
case that loads is a case that builds.

The structure (:class:`gear_fmu.system.GearShaftSystem`) still models the paper's layout only:
two shafts of one segment, one gear pair at mid-span, a bearing at each shaft end
(``_paper_layout`` says what else a case has); bearings 1, 2 on the driver's shaft (turning
about +z), 3, 4 on the driven one (about -z, mirrored local frame, :mod:`bearing_fmu.frames`).
"""

from __future__ import annotations

import math

from bearing_fmu import BearingData, BearingModel, model_class
from bearing_fmu.frames import LocalFrame
from fmu_src import train
from fmu_src.case import Case, CaseError, model_option_fields
from gear_fmu.layout import Layout, LayoutError
from gear_fmu.loads import StructureLoads
from gear_fmu.mesh.element import MeshElement, ToothDeviations
from gear_fmu.mesh.geometry import GearGeometryError, GearPair
from gear_fmu.structure import Structure
from gear_fmu.system import GearBody, GearShaftSystem, Shaft

__all__ = [
    "BEARING_FRAMES",
    "bearing_data",
    "bearing_frames",
    "bearing_models",
    "bearing_options",
    "bearing_parameters",
    "bearing_speeds",
    "damping",
    "drivetrain",
    "gear_pair",
    "gear_pairs",
    "gear_shaft_system",
    "layout",
    "mesh_element",
    "mesh_period",
    "mesh_teeth",
    "shared_bearing_model",
    "structure",
    "structure_loads",
    "time_step",
]

#: local frame of the bearings 1-4 of the paper's layout in the global (s, t) plane
#: (:func:`bearing_frames` gives any case's)
# TODO(train): the gear-shaft FMU's calculated parameters still take these four
BEARING_FRAMES = (LocalFrame(0.0, 1), LocalFrame(0.0, 1), LocalFrame(0.0, -1),
                  LocalFrame(0.0, -1))


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


def _paper_layout(case: Case) -> Layout:
    """The case's layout, if the structure can model it: the paper's (module docstring).
    TODO(train): goes once gear_fmu.system builds any layout."""
    lay = layout(case)
    why = []
    if len(lay.shafts) != 2 or len(lay.meshes) != 1 or lay.discs:
        why.append(f"{len(lay.shafts)} shafts, {len(lay.meshes)} meshes and "
                   f"{len(lay.discs)} discs")
    for s in lay.shafts:
        on = sorted(b.position for b in lay.bearings if b.shaft == s.name)
        gears = [g for g in lay.gears if g.shaft == s.name]
        if len(s.lengths) != 1 or on != [0.0, s.length] or len(gears) != 1 \
                or abs(gears[0].position - 0.5 * s.length) > 1e-9:
            why.append(f"shaft {s.name} (segments, bearings, gear)")
    if not why and any(g.unbalance_phase for g in lay.gears):
        why.append("an unbalance phase")
    if why:
        raise CaseError(f"{case.source}: the structure models the paper's layout only (two "
                        "shafts of one segment, a gear at mid-span of each, a bearing at each "
                        f"end), not {', '.join(why)}: the train's structure is on its way")
    return lay


def gear_pair(case: Case) -> GearPair:
    """The gear pair of a case of one mesh (:func:`gear_pairs` gives every mesh's).
    TODO(train): the callers of a single pair."""
    pairs = gear_pairs(case)
    if len(pairs) != 1:
        raise CaseError(f"{case.source}: {len(pairs)} meshes: the structure models one gear "
                        "pair for now (the train's structure is on its way; gear_pairs gives "
                        "each mesh's pair)")
    return pairs[0]


def gear_shaft_system(case: Case, pair: GearPair | None = None) -> GearShaftSystem:
    """The shafts and gear bodies -> :class:`gear_fmu.system.GearShaftSystem` (the paper's
    layout, ``_paper_layout``; driver's shaft first)."""
    lay = _paper_layout(case)
    pair = gear_pair(case) if pair is None else pair
    gears = [lay.gear(g) for g in lay.drivers[0]]
    shafts = [lay.shaft(g.shaft) for g in gears]
    return GearShaftSystem(
        shafts=tuple(Shaft(s.section(0), s.length, round(s.length / s.element_length))
                     for s in shafts),
        gears=tuple(GearBody(g.mass, r, b, s.density, g.polar_inertia, g.diametral_inertia)
                    for g, s, r, b in zip(gears, shafts, pair.pitch_radius, pair.face_width,
                                          strict=True)),  # type: ignore[arg-type]
        centre_distance=pair.centre_distance, teeth=pair.teeth,
        helix_angle_deg=math.degrees(pair.helix_angle), drivetrain=lay.drive.drivetrain,
        axial_stiffness=shafts[0].axial_stiffness)


def structure_loads(case: Case) -> StructureLoads:
    """Operating point (Sec. 4.1) -> :class:`gear_fmu.loads.StructureLoads`: each gear's
    unbalance as the eccentricity of its shaft with all it carries (Eq. 10)."""
    lay = _paper_layout(case)
    unbalance = []
    for name in lay.drivers[0]:
        g = lay.gear(name)
        scale = 1.0 if g.unbalance_mass == "shaft" else g.mass / lay.carried_mass(g.shaft)
        unbalance.append(g.unbalance * scale)
    gravity = tuple(lay.drive.gravity)
    return StructureLoads(torque=lay.drive.torque, input_speed=lay.drive.speed,
                          unbalance=tuple(unbalance),
                          gravity=gravity if any(gravity) else None)


def _deviations(lay: Layout, i: int) -> ToothDeviations | None:
    """The tooth deviations of mesh ``i`` (driver first), None when it has none."""
    mesh = lay.meshes[i]
    a, b = (lay.gear(g) for g in lay.drivers[i])
    dev = ToothDeviations(
        tip_relief=(a.tip_relief, b.tip_relief), relief_length=(a.relief_length,
                                                                b.relief_length),
        relief_exponent=mesh.relief_exponent, crowning=mesh.crowning,
        lead_slope=mesh.lead_slope, pitch_errors=(a.pitch_errors, b.pitch_errors),
        runout=(a.runout, b.runout), runout_phase=(a.runout_phase, b.runout_phase))
    return None if dev == ToothDeviations(relief_exponent=mesh.relief_exponent) else dev


def mesh_element(case: Case, pair: GearPair | None = None) -> MeshElement:
    """The distributed mesh element, contact term linearised at the nominal line load.
    TODO(train): one per mesh, in the pair's frame (gear_fmu.mesh.element.pair_frame)."""
    lay = layout(case)
    pair = gear_pair(case) if pair is None else pair
    return MeshElement(pair, pair.nominal_line_load(max(case["drive.torque"], 1.0)),
                       n_slices=lay.meshes[0].slices, deviations=_deviations(lay, 0))


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
    """Mesh period of the fastest mesh, ``2 pi / (|omega_driver| z_driver)`` [s]."""
    lay = layout(case)
    frequency = max(abs(float(lay.speeds[lay.shaft_index[lay.gear(d).shaft]]))
                    * lay.gear(d).teeth for d, _ in lay.drivers)
    return 2.0 * math.pi / frequency


def mesh_teeth(case: Case) -> list[tuple[int, int]]:
    """The teeth of each mesh's gears, driver first, in the layout's order."""
    lay = layout(case)
    return [(lay.gear(d).teeth, lay.gear(n).teeth) for d, n in lay.drivers]


def time_step(case: Case) -> float:
    """Time step of the case: the mesh period / ``simulation.steps_per_mesh_period`` [s]."""
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


def bearing_frames(case: Case) -> list[LocalFrame]:
    """The local frame of each bearing (its x axis along s; mirrored on a shaft turning about
    -z, :mod:`bearing_fmu.frames`), in the case's bearing order."""
    lay = layout(case)
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
