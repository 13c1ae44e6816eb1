"""The gear train as data: shafts, gears, meshes, bearings, discs and the drive (one layout).

A :class:`Layout` is the single source of the topology of a parallel-axis gear train; the
structure (:mod:`gear_fmu.system`), the mesh elements, the bearing frames and speeds, the FMU
ports and the results' labels all derive from it. It is plain data in SI units, built once from
a case (:func:`fmu_src.description.layout`), and checked on construction: every error is a
:class:`LayoutError` that names the component, the field and the limit.

Conventions
-----------
* Global frame (s, t, z) (:mod:`gear_fmu.dofs`): z along every shaft axis. The input shaft's
  axis passes through (s, t) = (0, 0); the shaft of the second gear of a mesh lies at the
  mesh's ``centre_distance`` from the shaft of its first gear, in the direction ``direction``
  (the angle from the s axis to the line of centres, in the s-t plane). For the paper's pair,
  pinion first and ``direction`` 0, the gear shaft lies at (a, 0) (Fig. 1).
* Axial positions are measured along each shaft from its start (``0 .. shaft.length``); the
  start lies at global ``z = shaft.offset``.
* Speeds and turning directions follow from the gear graph: the input shaft turns about +z at
  ``drive.speed``; across an external mesh the speed magnitude scales by
  ``z_driver / z_driven`` and the direction flips. The driver of a mesh is its gear on the
  shaft nearer the input: torque flows from the input shaft to the output shaft through every
  mesh (a mesh off that path would carry no torque and rattle: refused for now).
* The gear graph (shafts as vertices, meshes as edges) must be a tree spanning every shaft: a
  closed loop (a planetary stage) is refused for now; internal gears and carriers would add
  kinds of mesh, not change this data.
"""

from __future__ import annotations

import difflib
import itertools
import math
import re
from collections import deque
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from gear_fmu.drivetrain import Drivetrain
from gear_fmu.timoshenko import HollowSection

__all__ = ["HANDS", "PAIR_FIELDS", "UNBALANCE_MASSES", "BearingSpec", "DiscSpec", "Drive",
           "GearSpec", "Layout", "LayoutError", "MeshSpec", "ShaftSpec", "check_name"]

#: helix hands of a gear ("" for a spur gear)
HANDS = ("right", "left", "")
#: which mass carries a body's unbalance eccentricity: the body's own, or that of the shaft
#: with everything on it (the paper's Eq. 10: M = shaft + gear)
UNBALANCE_MASSES = ("body", "shaft")
_NAME = re.compile(r"^[A-Za-z0-9_]+$")
#: positions closer than this are the same position [m]
_SAME = 1e-9


#: what the two gears of a mesh share: (GearSpec field, unit in messages, factor to it)
PAIR_FIELDS = (("module", " mm", 1e3), ("pressure_angle", " deg", 180.0 / math.pi),
               ("helix_angle", " deg", 180.0 / math.pi), ("addendum_coefficient", "", 1.0),
               ("dedendum_coefficient", "", 1.0))


class LayoutError(ValueError):
    """A gear train that cannot be modelled; the message names the component and the field."""


def _unknown(where: str, kind: str, name: str, names) -> LayoutError:
    """The error for a name that is no ``kind`` of the train, the closest one as a hint."""
    names = list(names)
    close = difflib.get_close_matches(str(name), names, n=1, cutoff=0.6)
    hint = f"; did you mean {close[0]}?" if close else ""
    return LayoutError(f"{where} = {name!r}: no such {kind}{hint} ({kind}s: "
                       f"{', '.join(names) or 'none'})")


def check_name(kind: str, name: str) -> None:
    """A :class:`LayoutError` unless ``name`` (of a ``kind``: "shaft", "gear", ...) is made of
    letters, digits and ``_``."""
    if not isinstance(name, str) or not _NAME.match(name):
        raise LayoutError(f"{kind} name {name!r}: use letters, digits and _ only (it names "
                          "FMU ports, result labels and files)")


def _finite(where: str, value: float, unit: str, minimum: float = -math.inf,
            exclusive: bool = False) -> None:
    ok = math.isfinite(value) and (value > minimum if exclusive else value >= minimum)
    if not ok:
        sign = ">" if exclusive else ">="
        raise LayoutError(f"{where} = {value!r} {unit}: must be finite and {sign} {minimum:g}")


@dataclass(frozen=True)
class ShaftSpec:
    """A stepped shaft: segments of hollow circular section, one material.

    ``lengths``, ``outer_diameters``, ``inner_diameters``: per segment, from the shaft's start
    [m]; ``element_length``: the longest Timoshenko element [m]; ``offset``: global z of the
    start [m]; ``axial_stiffness``: the thrust spring on w at the shaft's first bearing [N/m].
    """

    name: str
    lengths: tuple[float, ...]
    outer_diameters: tuple[float, ...]
    inner_diameters: tuple[float, ...]
    young: float
    poisson: float
    density: float
    element_length: float
    offset: float = 0.0
    axial_stiffness: float = 1e9

    def __post_init__(self) -> None:
        check_name("shaft", self.name)
        where = f"shafts.{self.name}"
        n = len(self.lengths)
        if n < 1 or len(self.outer_diameters) != n or len(self.inner_diameters) != n:
            raise LayoutError(f"{where}: length, outer_diameter and inner_diameter need one "
                              f"value per segment ({n} lengths, {len(self.outer_diameters)} "
                              f"outer and {len(self.inner_diameters)} inner diameters)")
        for i, (ln, do, di) in enumerate(zip(self.lengths, self.outer_diameters,
                                             self.inner_diameters, strict=True)):
            _finite(f"{where}.length[{i + 1}]", ln, "m", 0.0, True)
            _finite(f"{where}.outer_diameter[{i + 1}]", do, "m", 0.0, True)
            _finite(f"{where}.inner_diameter[{i + 1}]", di, "m", 0.0)
            if di >= do:
                raise LayoutError(f"{where}.inner_diameter[{i + 1}] = {di!r} m must be smaller "
                                  f"than outer_diameter[{i + 1}] = {do!r} m")
        _finite(f"{where}.element_length", self.element_length, "m", 0.0, True)
        _finite(f"{where}.axial_stiffness", self.axial_stiffness, "N/m", 0.0, True)
        _finite(f"{where}.offset", self.offset, "m")

    @property
    def length(self) -> float:
        """Overall length [m]."""
        return float(sum(self.lengths))

    @property
    def breaks(self) -> tuple[float, ...]:
        """Positions of the segment ends from the start [m] (``len(lengths) + 1`` values)."""
        out = [0.0]
        for ln in self.lengths:
            out.append(out[-1] + ln)
        return tuple(out)

    def section(self, i: int) -> HollowSection:
        """The cross-section of segment i."""
        return HollowSection(self.outer_diameters[i], self.inner_diameters[i], young=self.young,
                             poisson=self.poisson, density=self.density)

    def segment_at(self, a: float, b: float) -> int:
        """The segment holding the interval [a, b] (an element's ends) [m]."""
        mid = 0.5 * (a + b)
        breaks = self.breaks
        for i in range(len(self.lengths)):
            if mid <= breaks[i + 1]:
                return i
        return len(self.lengths) - 1

    @property
    def mass(self) -> float:
        """Mass of the shaft alone [kg]."""
        return float(sum(self.section(i).mass_per_length * ln
                         for i, ln in enumerate(self.lengths)))


@dataclass(frozen=True)
class GearSpec:
    """A gear body and its teeth on a shaft (paper Table 1 for one wheel).

    ``position``: face centre from the shaft's start [m]; ``module`` the normal module [m];
    ``pressure_angle``, ``helix_angle`` [rad] (helix >= 0, its ``hand`` "right" or "left";
    "" for spur gears); ``face_width`` [m]; ``mass`` [kg]; ``polar_inertia``,
    ``diametral_inertia`` [kg m^2] (0: those of a steel annulus,
    :func:`gear_fmu.system.annulus_inertias`); ``unbalance`` eccentricity [m] of the mass
    ``unbalance_mass`` (:data:`UNBALANCE_MASSES`) at angle ``unbalance_phase`` [rad] at t = 0;
    tooth deviations: ``tip_relief``, ``relief_length`` [m], ``pitch_errors`` (one per tooth or
    none) [m], ``runout`` [m] at ``runout_phase`` [rad]
    (:class:`gear_fmu.mesh.element.ToothDeviations`).
    """

    name: str
    shaft: str
    position: float
    teeth: int
    module: float
    pressure_angle: float
    face_width: float
    mass: float
    helix_angle: float = 0.0
    hand: str = ""
    profile_shift: float = 0.0
    addendum_coefficient: float = 1.0
    dedendum_coefficient: float = 1.25
    polar_inertia: float = 0.0
    diametral_inertia: float = 0.0
    unbalance: float = 0.0
    unbalance_phase: float = 0.0
    unbalance_mass: str = "body"
    tip_relief: float = 0.0
    relief_length: float = 0.0
    pitch_errors: tuple = ()
    runout: float = 0.0
    runout_phase: float = 0.0

    def __post_init__(self) -> None:
        check_name("gear", self.name)
        where = f"gears.{self.name}"
        if self.hand not in HANDS:
            raise LayoutError(f"{where}.hand = {self.hand!r}: one of right, left")
        if self.helix_angle > 0.0 and not self.hand:
            raise LayoutError(f"{where}: a helical gear (helix_angle "
                              f"{math.degrees(self.helix_angle):g} deg) needs its hand: right "
                              "or left")
        if self.unbalance_mass not in UNBALANCE_MASSES:
            raise LayoutError(f"{where}.unbalance_mass = {self.unbalance_mass!r}: one of "
                              f"{', '.join(UNBALANCE_MASSES)}")
        if self.pitch_errors and len(self.pitch_errors) != self.teeth:
            raise LayoutError(f"{where}.pitch_errors: {len(self.pitch_errors)} values for "
                              f"{self.teeth} teeth (one per tooth, or none)")
        for key, unit in (("unbalance", "m"), ("tip_relief", "m"), ("relief_length", "m"),
                          ("runout", "m")):
            _finite(f"{where}.{key}", getattr(self, key), unit, 0.0)
        if self.tip_relief > 0.0 and self.relief_length <= 0.0:
            raise LayoutError(f"{where}.tip_relief = {self.tip_relief!r} m needs "
                              f"{where}.relief_length > 0 (its extent along the line of action)")

    @property
    def extent(self) -> tuple[float, float]:
        """Axial extent of the face from the shaft's start [m]."""
        return self.position - 0.5 * self.face_width, self.position + 0.5 * self.face_width


@dataclass(frozen=True)
class MeshSpec:
    """A mesh between two gears on different shafts.

    ``centre_distance`` [m]: the operating one; ``direction`` [rad]: the angle from the s axis
    to the line of centres, from the shaft of ``gears[0]`` to that of ``gears[1]``;
    ``slices``: slices across the face width (:class:`gear_fmu.mesh.element.MeshElement`);
    ``crowning``, ``lead_slope`` [m] and ``relief_exponent`` (1 linear, 2 parabolic): the
    pair's deviations.
    """

    name: str
    gears: tuple[str, str]
    centre_distance: float
    direction: float = 0.0
    slices: int = 20
    crowning: float = 0.0
    lead_slope: float = 0.0
    relief_exponent: float = 2.0

    def __post_init__(self) -> None:
        check_name("mesh", self.name)
        if len(self.gears) != 2:
            raise LayoutError(f"meshes.{self.name}.gears: two gear names, got "
                              f"{len(self.gears)}")
        _finite(f"meshes.{self.name}.centre_distance", self.centre_distance, "m", 0.0, True)
        _finite(f"meshes.{self.name}.direction", self.direction, "rad")
        if self.relief_exponent not in (1.0, 2.0):
            raise LayoutError(f"meshes.{self.name}.relief_exponent = {self.relief_exponent!r}: "
                              "1 (linear) or 2 (parabolic)")


@dataclass(frozen=True)
class BearingSpec:
    """A journal bearing on a shaft: its model (:data:`bearing_fmu.MODELS`), geometry,
    lubricant and the model's options (``options``: ``((key, value), ...)``).

    ``position`` [m] from the shaft's start; ``diameter``, ``length``, ``clearance`` [m];
    ``viscosity`` [Pa s].
    """

    name: str
    shaft: str
    position: float
    model: str
    diameter: float
    length: float
    clearance: float
    viscosity: float
    options: tuple = ()

    def __post_init__(self) -> None:
        check_name("bearing", self.name)
        where = f"bearings.{self.name}"
        for key, unit in (("diameter", "m"), ("length", "m"), ("clearance", "m"),
                          ("viscosity", "Pa.s")):
            _finite(f"{where}.{key}", getattr(self, key), unit, 0.0, True)
        if self.clearance >= 0.5 * self.diameter:
            raise LayoutError(f"{where}.clearance = {self.clearance!r} m must be smaller than "
                              f"the bearing radius {0.5 * self.diameter!r} m")

    @property
    def option_dict(self) -> dict:
        """The model's options as ``{key: value}``."""
        return dict(self.options)

    @property
    def extent(self) -> tuple[float, float]:
        """Axial extent from the shaft's start [m]."""
        return self.position - 0.5 * self.length, self.position + 0.5 * self.length


@dataclass(frozen=True)
class DiscSpec:
    """A rigid disc (coupling hub, impeller, ...) on a shaft: ``mass`` [kg], inertias
    [kg m^2], ``unbalance`` eccentricity [m] of ``unbalance_mass`` at ``unbalance_phase``
    [rad], ``position`` [m] from the shaft's start."""

    name: str
    shaft: str
    position: float
    mass: float
    polar_inertia: float = 0.0
    diametral_inertia: float = 0.0
    unbalance: float = 0.0
    unbalance_phase: float = 0.0
    unbalance_mass: str = "body"

    def __post_init__(self) -> None:
        check_name("disc", self.name)
        where = f"discs.{self.name}"
        _finite(f"{where}.mass", self.mass, "kg", 0.0)
        _finite(f"{where}.polar_inertia", self.polar_inertia, "kg.m^2", 0.0)
        _finite(f"{where}.diametral_inertia", self.diametral_inertia, "kg.m^2", 0.0)
        _finite(f"{where}.unbalance", self.unbalance, "m", 0.0)
        if self.unbalance_mass not in UNBALANCE_MASSES:
            raise LayoutError(f"{where}.unbalance_mass = {self.unbalance_mass!r}: one of "
                              f"{', '.join(UNBALANCE_MASSES)}")

    @property
    def extent(self) -> tuple[float, float]:
        """Axial extent from the shaft's start [m] (a disc has no width here)."""
        return self.position, self.position


@dataclass(frozen=True)
class Drive:
    """Where the power enters and leaves: the input ``speed`` [rad/s] and ``torque`` [N m] on
    the torsion DOF of ``input_shaft`` at ``input_position`` (from its start [m]; None: its
    start), the resisting torque at ``output_shaft``'s ``output_position`` (None: its end),
    the motor and load of ``drivetrain`` (:class:`gear_fmu.drivetrain.Drivetrain`) there, and
    ``gravity`` (g_s, g_t) [m/s^2]."""

    input_shaft: str
    output_shaft: str
    speed: float
    torque: float
    input_position: float | None = None
    output_position: float | None = None
    drivetrain: Drivetrain = field(default_factory=Drivetrain)
    gravity: tuple = (0.0, 0.0)  # (g_s, g_t); "tuple[float, float]" breaks the API docs

    def __post_init__(self) -> None:
        _finite("drive.speed", self.speed, "rad/s", 0.0)
        _finite("drive.torque", self.torque, "N.m")
        if len(self.gravity) != 2:
            raise LayoutError(f"drive.gravity = {self.gravity!r}: two components (g_s, g_t)")
        for i, g in enumerate(self.gravity):
            _finite(f"drive.gravity[{i + 1}]", g, "m/s^2")


@dataclass(frozen=True)
class Layout:
    """A parallel-axis gear train (module docstring), checked on construction."""

    shafts: tuple[ShaftSpec, ...]
    gears: tuple[GearSpec, ...]
    meshes: tuple[MeshSpec, ...]
    bearings: tuple[BearingSpec, ...]
    drive: Drive
    discs: tuple[DiscSpec, ...] = ()

    def __post_init__(self) -> None:
        for kind, items in (("shaft", self.shafts), ("gear", self.gears),
                            ("mesh", self.meshes), ("bearing", self.bearings),
                            ("disc", self.discs)):
            seen = set()
            for item in items:
                if item.name in seen:
                    raise LayoutError(f"two {kind}s named {item.name!r}")
                seen.add(item.name)
        if not self.shafts:
            raise LayoutError("the train has no shaft")
        self._check_places()
        self._check_graph()
        self._check_bearings()

    # ------------------------------------------------------------------ lookups
    @cached_property
    def shaft_index(self) -> dict[str, int]:
        """Shaft name -> index in ``shafts``."""
        return {s.name: i for i, s in enumerate(self.shafts)}

    @cached_property
    def gear_index(self) -> dict[str, int]:
        """Gear name -> index in ``gears``."""
        return {g.name: i for i, g in enumerate(self.gears)}

    def shaft(self, name: str) -> ShaftSpec:
        return self.shafts[self.shaft_index[name]]

    def gear(self, name: str) -> GearSpec:
        return self.gears[self.gear_index[name]]

    @property
    def bearing_names(self) -> tuple[str, ...]:
        return tuple(b.name for b in self.bearings)

    @property
    def mesh_names(self) -> tuple[str, ...]:
        return tuple(m.name for m in self.meshes)

    # ------------------------------------------------------------------ checks
    def _shaft_of(self, kind: str, item) -> ShaftSpec:
        if item.shaft not in self.shaft_index:
            raise _unknown(f"{kind}.{item.name}.shaft", "shaft", item.shaft, self.shaft_index)
        return self.shaft(item.shaft)

    def _check_places(self) -> None:
        """Every gear, disc and bearing on an existing shaft, inside it, none on another."""
        on_shaft: dict[str, list] = {s.name: [] for s in self.shafts}
        for kind, items in (("gears", self.gears), ("bearings", self.bearings),
                            ("discs", self.discs)):
            for item in items:
                shaft = self._shaft_of(kind, item)
                if not (-_SAME <= item.position <= shaft.length + _SAME):
                    raise LayoutError(
                        f"{kind}.{item.name}.position = {item.position * 1e3:.6g} mm lies "
                        f"outside its shaft {shaft.name} (0 to {shaft.length * 1e3:.6g} mm)")
                on_shaft[shaft.name].append((item.extent, f"{kind[:-1]} {item.name}",
                                             item.position))
        for shaft, items in on_shaft.items():
            items.sort(key=lambda it: it[0])
            for (ext_a, name_a, pos_a), (ext_b, name_b, pos_b) in itertools.pairwise(items):
                if ext_b[0] < ext_a[1] - _SAME or abs(pos_a - pos_b) <= _SAME:
                    raise LayoutError(
                        f"{name_a} ({ext_a[0] * 1e3:.6g} to {ext_a[1] * 1e3:.6g} mm) and "
                        f"{name_b} ({ext_b[0] * 1e3:.6g} to {ext_b[1] * 1e3:.6g} mm) overlap "
                        f"on shaft {shaft}: move one of them")
        d = self.drive
        for key, name, pos in (("input", d.input_shaft, d.input_position),
                               ("output", d.output_shaft, d.output_position)):
            if name not in self.shaft_index:
                raise _unknown(f"drive.{key}_shaft", "shaft", name, self.shaft_index)
            length = self.shaft(name).length
            if pos is not None and not (-_SAME <= pos <= length + _SAME):
                raise LayoutError(f"drive.{key}_position = {pos * 1e3:.6g} mm lies outside "
                                  f"shaft {name} (0 to {length * 1e3:.6g} mm)")

    def _check_graph(self) -> None:
        """Meshes between gears of different shafts forming a tree over every shaft, every
        mesh on the power path from the input to the output."""
        used: set[str] = set()
        for m in self.meshes:
            for g in m.gears:
                if g not in self.gear_index:
                    raise _unknown(f"meshes.{m.name}.gears", "gear", g, self.gear_index)
                used.add(g)
            a, b = (self.gear(g).shaft for g in m.gears)
            if a == b:
                raise LayoutError(f"meshes.{m.name}: gears {m.gears[0]} and {m.gears[1]} are "
                                  f"both on shaft {a}; a mesh joins gears of two shafts")
            self._check_pair(m)
            za, zb = (self.shaft(self.gear(g).shaft).offset + self.gear(g).position
                      for g in m.gears)
            if abs(za - zb) > 1e-6:
                raise LayoutError(
                    f"meshes.{m.name}: the face centres of gears {m.gears[0]} and {m.gears[1]} "
                    f"lie at global z = {za * 1e3:.6g} and {zb * 1e3:.6g} mm: meshing gears "
                    "share their face centre (shaft offset + gear position)")
        unused = [g.name for g in self.gears if g.name not in used]
        if unused:
            raise LayoutError(f"gear {unused[0]} is in no mesh (a body without teeth is a "
                              "disc: [discs])")
        # a tree spanning every shaft, from the input shaft
        parent: dict[str, tuple] = {self.drive.input_shaft: (None, None)}
        queue = deque([self.drive.input_shaft])
        adj: dict[str, list] = {s.name: [] for s in self.shafts}
        for m in self.meshes:
            a, b = (self.gear(g).shaft for g in m.gears)
            adj[a].append((b, m))
            adj[b].append((a, m))
        while queue:
            s = queue.popleft()
            for other, m in adj[s]:
                if parent[s][1] is m:
                    continue
                if other in parent:
                    raise LayoutError(
                        f"the meshes form a closed loop through shafts {s} and {other} (mesh "
                        f"{m.name}): a planetary stage or any closed gear loop is not "
                        "supported yet; the gear graph must be a tree")
                parent[other] = (s, m)
                queue.append(other)
        apart = [s.name for s in self.shafts if s.name not in parent]
        if apart:
            raise LayoutError(
                f"shaft{'s' if len(apart) > 1 else ''} {', '.join(apart)} not joined to the "
                f"input shaft {self.drive.input_shaft} by meshes: two separate trains (one "
                "train per case)")
        object.__setattr__(self, "_parent", parent)
        path = self.power_path
        off = [m.name for m in self.meshes if m.name not in {pm.name for pm in path}]
        if off:
            raise LayoutError(
                f"mesh {off[0]} is not between the input shaft {self.drive.input_shaft} and "
                f"the output shaft {self.drive.output_shaft}: it would carry no torque (a "
                "loose branch rattles, not modelled yet)")

    def _check_pair(self, m: MeshSpec) -> None:
        """The two gears of an (external) mesh cut by one rack: the same module, pressure
        angle, helix angle and tooth proportions (:data:`PAIR_FIELDS`); helical, of opposite
        hands."""
        a, b = (self.gear(g) for g in m.gears)
        for key, unit, scale in PAIR_FIELDS:
            va, vb = getattr(a, key), getattr(b, key)
            if not math.isclose(va, vb, rel_tol=1e-12, abs_tol=1e-15):
                raise LayoutError(
                    f"meshes.{m.name}: gears.{a.name}.{key} = {va * scale:.9g}{unit} and "
                    f"gears.{b.name}.{key} = {vb * scale:.9g}{unit} differ: the two gears of "
                    f"a mesh share {', '.join(k for k, _, _ in PAIR_FIELDS)}")
        if a.helix_angle > 0.0 and a.hand == b.hand:
            raise LayoutError(
                f"meshes.{m.name}: gears.{a.name}.hand and gears.{b.name}.hand are both "
                f"{a.hand!r}: the gears of an external helical pair have opposite hands")

    def _check_bearings(self) -> None:
        for s in self.shafts:
            n = sum(b.shaft == s.name for b in self.bearings)
            if n < 2:
                raise LayoutError(
                    f"shaft {s.name} has {n} bearing{'s' if n != 1 else ''}: at least two hold "
                    "a shaft radially (radial couplings are not modelled)")

    # ------------------------------------------------------------------ derived topology
    @cached_property
    def power_path(self) -> tuple[MeshSpec, ...]:
        """The meshes from the input shaft to the output shaft, in the order power crosses
        them."""
        parent = self._parent
        out = []
        s = self.drive.output_shaft
        while parent[s][0] is not None:
            out.append(parent[s][1])
            s = parent[s][0]
        return tuple(reversed(out))

    @cached_property
    def drivers(self) -> tuple[tuple[str, str], ...]:
        """Per mesh ``(driver gear, driven gear)``: the driver on the shaft nearer the
        input."""
        parent = self._parent
        out = []
        for m in self.meshes:
            g0, g1 = m.gears
            s1 = self.gear(g1).shaft
            out.append((g0, g1) if parent[s1][1] is m else (g1, g0))
        return tuple(out)

    @cached_property
    def speeds(self) -> np.ndarray:
        """Signed speed of each shaft about +z [rad/s] (order of ``shafts``)."""
        w = {self.drive.input_shaft: self.drive.speed}
        for m in self._mesh_order():
            drv, dvn = self.drivers[self.meshes.index(m)]
            gd, gn = self.gear(drv), self.gear(dvn)
            w[gn.shaft] = -w[gd.shaft] * gd.teeth / gn.teeth
        return np.array([w[s.name] for s in self.shafts])

    @cached_property
    def directions(self) -> np.ndarray:
        """Turning direction of each shaft (+1 about +z, -1 about -z), from the gear graph
        (defined at zero speed too)."""
        sign = {self.drive.input_shaft: 1}
        for m in self._mesh_order():
            drv, dvn = self.drivers[self.meshes.index(m)]
            sign[self.gear(dvn).shaft] = -sign[self.gear(drv).shaft]
        return np.array([sign[s.name] for s in self.shafts], dtype=int)

    @cached_property
    def ratios(self) -> np.ndarray:
        """Speed magnitude of each shaft over the input speed [-]."""
        r = {self.drive.input_shaft: 1.0}
        for m in self._mesh_order():
            drv, dvn = self.drivers[self.meshes.index(m)]
            gd, gn = self.gear(drv), self.gear(dvn)
            r[gn.shaft] = r[gd.shaft] * gd.teeth / gn.teeth
        return np.array([r[s.name] for s in self.shafts])

    def _mesh_order(self) -> list[MeshSpec]:
        """The meshes in breadth-first order from the input shaft (each driver's speed known
        before its mesh)."""
        parent = self._parent
        depth = {}
        for s in parent:
            d, x = 0, s
            while parent[x][0] is not None:
                d += 1
                x = parent[x][0]
            depth[s] = d
        return sorted(self.meshes, key=lambda m: max(depth[self.gear(g).shaft]
                                                     for g in m.gears))

    @cached_property
    def shaft_centres(self) -> np.ndarray:
        """(n_shafts, 2) position (s, t) of each shaft axis [m]."""
        pos = {self.drive.input_shaft: np.zeros(2)}
        for m in self._mesh_order():
            a, b = (self.gear(g).shaft for g in m.gears)
            e = np.array([math.cos(m.direction), math.sin(m.direction)])
            if a in pos:
                pos[b] = pos[a] + m.centre_distance * e
            else:
                pos[a] = pos[b] - m.centre_distance * e
        return np.array([pos[s.name] for s in self.shafts])

    def torque_on(self, shaft: str) -> float:
        """Torque the train transmits along ``shaft`` [N m] (magnitude): the input torque times
        the speed ratio input / shaft (no losses)."""
        return self.drive.torque / float(self.ratios[self.shaft_index[shaft]])

    @property
    def input_position(self) -> float:
        """Where the input torque acts on the input shaft [m from its start]."""
        p = self.drive.input_position
        return 0.0 if p is None else p

    @property
    def output_position(self) -> float:
        """Where the resisting torque acts on the output shaft [m from its start]."""
        p = self.drive.output_position
        return self.shaft(self.drive.output_shaft).length if p is None else p

    def carried_mass(self, shaft: str) -> float:
        """Mass of a shaft with every gear and disc on it [kg] (the M of Eq. 10)."""
        s = self.shaft(shaft)
        return s.mass + sum(g.mass for g in self.gears if g.shaft == shaft) + sum(
            d.mass for d in self.discs if d.shaft == shaft)
