"""A case's values -> the gear train and the objects that check it: the layout
(:class:`gear_fmu.layout.Layout`), one gear pair per mesh, the drivetrain and the damping
model.

The case loader (:mod:`fmu_src.case`) builds them to check a case, and
:mod:`fmu_src.description` builds the system with these same functions (it re-exports them,
naming the case's file in their errors): a case that loads is a case that builds. They take a
:class:`fmu_src.case.Case` or its ``values`` (SI, keyed ``shafts.<name>.length``, ...) and
raise :class:`gear_fmu.layout.LayoutError`, :class:`gear_fmu.mesh.geometry.GearGeometryError`
or ``ValueError`` with messages that name the case's fields.

Every field of a gear, mesh, bearing and disc table has the name of the attribute it sets on
its :mod:`gear_fmu.layout` spec (a shaft's ``length``, ``outer_diameter``, ... set
``lengths``, ``outer_diameters``, ...: :data:`SHAFT_FIELDS`).
"""

from __future__ import annotations

import math
from dataclasses import fields

from bearing_fmu import model_class
from fmu_src.fields import instance_names
from gear_fmu.drivetrain import Drivetrain
from gear_fmu.layout import BearingSpec, DiscSpec, Drive, GearSpec, Layout, MeshSpec, ShaftSpec
from gear_fmu.mesh.geometry import GearGeometryError, GearPair, zero_backlash_centre_distance
from gear_fmu.mesh.train import gear_pair
from gear_fmu.modal.damping import DampingModel

__all__ = ["SHAFT_FIELDS", "damping", "drivetrain", "gear_pair_of", "gear_pairs", "layout"]

#: ShaftSpec attribute -> shaft field of a case
SHAFT_FIELDS = {"lengths": "length", "outer_diameters": "outer_diameter",
                "inner_diameters": "inner_diameter", "young": "young_modulus",
                "poisson": "poisson_ratio", "density": "density",
                "element_length": "element_length", "offset": "offset",
                "axial_stiffness": "axial_stiffness"}
#: elements per shaft when ``element_length`` is 0
DEFAULT_ELEMENTS = 8


def _values(case) -> dict:
    """A case's values (a :class:`fmu_src.case.Case` or the values themselves)."""
    return case if isinstance(case, dict) else case.values


def _spec(cls, v: dict, section: str, name: str, rename: dict | None = None, **given):
    """A layout spec of class ``cls`` for instance ``name`` of ``section``: each attribute
    from the field of the same name (or ``rename[attribute]``), lists as tuples."""
    kw = {"name": name, **given}
    for f in fields(cls):
        if f.name not in kw:
            value = v[f"{section}.{name}.{(rename or {}).get(f.name, f.name)}"]
            kw[f.name] = tuple(value) if isinstance(value, list) else value
    return cls(**kw)


def _shaft(v: dict, name: str) -> ShaftSpec:
    element = v[f"shafts.{name}.element_length"]
    if not element:
        element = sum(v[f"shafts.{name}.length"]) / DEFAULT_ELEMENTS
    return _spec(ShaftSpec, v, "shafts", name, SHAFT_FIELDS, element_length=element)


def _bearing(v: dict, name: str) -> BearingSpec:
    model = v[f"bearings.{name}.model"]
    options = tuple((o.key, v[f"bearings.{name}.{o.key}"]) for o in model_class(model).options)
    return _spec(BearingSpec, v, "bearings", name, options=options)


def drivetrain(case) -> Drivetrain:
    """``drive.motor_*``, ``drive.output_end``, ``drive.load_*`` ->
    :class:`gear_fmu.drivetrain.Drivetrain` (one field per attribute, same name); its errors
    name the fields."""
    v = _values(case)
    try:
        return Drivetrain(**{f.name: v[f"drive.{f.name}"] for f in fields(Drivetrain)})
    except ValueError as exc:  # Drivetrain names its attributes drivetrain.<name>
        raise ValueError(str(exc).replace("drivetrain.", "drive.")) from None


def damping(case) -> DampingModel:
    """``simulation.damping_*``, ``rayleigh_*``, ``mesh_damping*`` fields ->
    :class:`gear_fmu.modal.damping.DampingModel`."""
    v = _values(case)
    try:
        return DampingModel(
            kind=v["simulation.damping_model"], ratio=v["simulation.damping_ratio"],
            basis=v["simulation.damping_basis"],
            rayleigh_frequencies=tuple(v["simulation.rayleigh_frequencies"]),
            rayleigh_alpha=v["simulation.rayleigh_alpha"],
            rayleigh_beta=v["simulation.rayleigh_beta"],
            mesh_ratio=v["simulation.mesh_damping_ratio"],
            mesh_coefficient=v["simulation.mesh_damping"])
    except ValueError as exc:
        raise ValueError(f"simulation damping fields: {exc}") from None


def layout(case) -> Layout:
    """The gear train of a case (:class:`gear_fmu.layout.Layout`, checked on construction)."""
    v = _values(case)

    def each(section):
        return instance_names(v, section)

    drive = Drive(input_shaft=v["drive.input_shaft"], output_shaft=v["drive.output_shaft"],
                  speed=v["drive.speed"], torque=v["drive.torque"],
                  input_position=v["drive.input_position"],
                  output_position=v["drive.output_position"], drivetrain=drivetrain(v),
                  gravity=tuple(v["drive.gravity"]))
    return Layout(shafts=tuple(_shaft(v, n) for n in each("shafts")),
                  gears=tuple(_spec(GearSpec, v, "gears", n) for n in each("gears")),
                  meshes=tuple(_spec(MeshSpec, v, "meshes", n) for n in each("meshes")),
                  bearings=tuple(_bearing(v, n) for n in each("bearings")),
                  discs=tuple(_spec(DiscSpec, v, "discs", n) for n in each("discs")),
                  drive=drive)


def gear_pair_of(lay: Layout, i: int) -> GearPair:
    """The :class:`gear_fmu.mesh.geometry.GearPair` of mesh ``i`` of a layout
    (:func:`gear_fmu.mesh.train.gear_pair`: its driver first, the teeth of the driver's
    shaft's material); a geometry error in the case's terms (the fields that set the mesh and
    the centre distance its profile shifts need)."""
    try:
        return gear_pair(lay, i)
    except GearGeometryError as exc:
        raise GearGeometryError(_geometry_message(lay, i, exc)) from None


def gear_pairs(case, lay: Layout | None = None) -> tuple[GearPair, ...]:
    """One gear pair per mesh, in the layout's order (``lay``: the case's layout, if built)."""
    lay = layout(case) if lay is None else lay
    return tuple(gear_pair_of(lay, i) for i in range(len(lay.meshes)))


def _geometry_message(lay: Layout, i: int, exc: Exception) -> str:
    """A gear-geometry error in the case's terms: the fields that set the mesh, and the centre
    distance at which the profile shifts would mesh without backlash."""
    mesh = lay.meshes[i]
    a, b = (lay.gear(g) for g in lay.drivers[i])
    centre = mesh.centre_distance
    shifts = [a.profile_shift, b.profile_shift]
    try:
        a0 = zero_backlash_centre_distance((a.teeth, b.teeth), a.module, a.pressure_angle,
                                           a.helix_angle, shifts)
    except (ValueError, ZeroDivisionError):
        a0 = math.nan
    hint = ""
    if math.isfinite(a0) and abs(a0 - centre) > 1e-6:
        hint = (f"; with gears.{a.name}.profile_shift = {shifts[0]:g} and "
                f"gears.{b.name}.profile_shift = {shifts[1]:g} the gears mesh without backlash "
                f"at meshes.{mesh.name}.centre_distance = {a0 * 1e3:.3f} mm: set that centre "
                f"distance or profile shifts that fit {centre * 1e3:.3f} mm")
    return (f"meshes.{mesh.name} (gears {a.name} and {b.name}: centre_distance = "
            f"{centre * 1e3:.3f} mm, profile_shift = {shifts}, addendum_coefficient = "
            f"{a.addendum_coefficient:g}, dedendum_coefficient = {a.dedendum_coefficient:g}): "
            f"{exc}{hint}")
