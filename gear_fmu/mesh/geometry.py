"""Involute geometry of an external spur or helical gear pair (paper Table 1, Sec. 2.1).

Frames (shared with :mod:`gear_fmu.mesh.element` and :mod:`gear_fmu.system`)
----------------------------------------------------------------------------
Global frame (s, t, z): pinion centre O1 = (0, 0), gear centre O2 = (a, 0), z along both axes.
A positive input torque turns the pinion about +z; the gear turns about -z. The transverse line
of action is the tangent to both base circles with unit vector ``u = (sin a', cos a')`` (a' the
operating transverse pressure angle); it touches the pinion base circle at
``T1 = rb1 (cos a', -sin a')`` and the gear base circle at ``T2 = T1 + |T1T2| u``,
``|T1T2| = a sin a'``. A contact point has the abscissa ``xi`` (distance from T1 along u): it
enters the path of contact at ``xi_A`` (gear tip) and leaves at ``xi_E`` (pinion tip).

Standard relations (ISO 21771), transverse quantities with suffix t:
``m_t = m_n / cos(beta)``, ``tan(alpha_t) = tan(alpha_n) / cos(beta)``, pitch radius
``r = m_t z / 2``, base radius ``r_b = r cos(alpha_t)``, ``tan(beta_b) = tan(beta) cos(alpha_t)``,
transverse base pitch ``p_bt = 2 pi r_b1 / z1``, tip radius ``r_a = r + m_n (h_a* + x)``, root
radius ``r_f = r - m_n (h_f* - x)``, operating angle ``cos(a') = (r_b1 + r_b2) / a``.

Table 1 reading: its 1.4 / 1.0 "addendum / dedendum" coefficients are those of the rack cutter, so
each wheel has addendum 1.0 m_n and dedendum 1.4 m_n (taken literally, addendum 1.4, the pinion
tips would cut 1.6 mm into the gear's root circle at a = 366 mm: :meth:`GearPair.check` rejects it).

Checks on input (:meth:`GearPair.check`, called on construction): the teeth must not overlap at
the given centre distance (backlash >= 0), the tips must clear the mating root circles, the
wheels must not be undercut by the generating rack (straight rack flank up to h_a* m_n), and the
path of contact must stay on the generated involutes of both wheels (no tip-to-root
interference) with a contact ratio above 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

__all__ = ["GearGeometryError", "GearPair", "involute"]


class GearGeometryError(ValueError):
    """Gear data that cannot mesh (interference, undercut, overlap); the message has the numbers."""


def involute(alpha: float) -> float:
    """Involute function inv(alpha) = tan(alpha) - alpha [rad]."""
    return math.tan(alpha) - alpha


def zero_backlash_centre_distance(teeth, module: float, pressure_angle: float,
                                  helix_angle: float, profile_shift) -> float:
    """Centre distance at which two gears with these profile shifts mesh without backlash [m]
    (ISO 21771: inv a'_t = inv a_t + 2 tan(a_n) (x1 + x2) / (z1 + z2),
    a' = (z1 + z2) m_n cos(a_t) / (2 cos(beta) cos(a'_t)))."""
    from scipy.optimize import brentq

    z = float(teeth[0]) + float(teeth[1])
    alpha_t = math.atan(math.tan(pressure_angle) / math.cos(helix_angle))
    target = involute(alpha_t) + 2.0 * math.tan(pressure_angle) * sum(profile_shift) / z
    if target <= 0.0:
        return float("nan")
    alpha_w = brentq(lambda a: involute(a) - target, 1e-9, 0.5 * math.pi - 1e-9, xtol=1e-15)
    return z * module * math.cos(alpha_t) / (2.0 * math.cos(helix_angle) * math.cos(alpha_w))


def _positive(name: str, value: float, unit: str) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0.0):
        raise GearGeometryError(f"{name} = {value!r} {unit}: must be finite and > 0")
    return value


@dataclass(frozen=True)
class GearPair:
    """An external involute gear pair, SI units.

    Parameters
    ----------
    teeth : (int, int)
        Numbers of teeth (pinion, gear).
    module : float
        Normal module m_n [m].
    pressure_angle : float
        Normal pressure angle alpha_n [rad].
    centre_distance : float
        Operating centre distance a [m].
    face_width : (float, float)
        Face widths (pinion, gear) [m]; both centred on the gear nodes (z = 0). The contact
        spans the common width ``min(b1, b2)``.
    helix_angle : float
        Helix angle beta [rad] (0: spur). The hand is fixed by the contact-line convention of
        :mod:`gear_fmu.mesh.element` (flank normal with a +z component ``sin(beta_b)``: the mesh
        pushes the gear towards +z and the pinion towards -z).
    profile_shift : (float, float)
        Profile shift coefficients (x1, x2) [-].
    addendum_coefficient, dedendum_coefficient : float
        h_a*, h_f* of the wheels [-] (Table 1: 1.0 and 1.4, see the module docstring).
    young, poisson : float
        Elastic constants of both wheels [Pa], [-] (tooth stiffness, :mod:`gear_fmu.mesh.element`).

    Examples
    --------
    A standard 20/40 pair at its reference centre distance (by hand: contact ratio 1.635, tip
    clearance 0.25 m_n = 0.75 mm; the paper's pair: :func:`fmu_src.examples.paper_gear_pair`):

    >>> g = GearPair(teeth=(20, 40), module=3e-3, pressure_angle=math.radians(20.0),
    ...              centre_distance=0.09, face_width=(0.03, 0.03))
    >>> round(g.transverse_contact_ratio, 3), round(g.tip_clearance[0] * 1e3, 2)
    (1.635, 0.75)
    """

    teeth: tuple[int, int]
    module: float
    pressure_angle: float
    centre_distance: float
    face_width: tuple[float, float]
    helix_angle: float = 0.0
    profile_shift: tuple[float, float] = (0.0, 0.0)
    addendum_coefficient: float = 1.0
    dedendum_coefficient: float = 1.25
    young: float = 210e9
    poisson: float = 0.3

    def __post_init__(self) -> None:
        z1, z2 = (int(z) for z in self.teeth)
        if z1 != self.teeth[0] or z2 != self.teeth[1] or min(z1, z2) < 5:
            raise GearGeometryError(f"teeth = {self.teeth!r}: two integers >= 5")
        _positive("module", self.module, "m")
        _positive("centre_distance", self.centre_distance, "m")
        for b in self.face_width:
            _positive("face_width", b, "m")
        if not 0.0 < self.pressure_angle < math.radians(40.0):
            raise GearGeometryError(
                f"pressure_angle = {self.pressure_angle!r} rad must lie in (0, 40 deg)")
        if not 0.0 <= self.helix_angle < math.radians(45.0):
            raise GearGeometryError(
                f"helix_angle = {self.helix_angle!r} rad must lie in [0, 45 deg)")
        for name in ("addendum_coefficient", "dedendum_coefficient"):
            _positive(name, getattr(self, name), "(-)")
        _positive("young", self.young, "Pa")
        if not 0.0 <= self.poisson < 0.5:
            raise GearGeometryError(f"poisson = {self.poisson!r} must lie in [0, 0.5)")
        self.check()

    # ------------------------------------------------------------------ basic quantities
    @property
    def ratio(self) -> float:
        """Gear ratio u = z2 / z1 [-]."""
        return self.teeth[1] / self.teeth[0]

    @cached_property
    def transverse_module(self) -> float:
        """m_t = m_n / cos(beta) [m]."""
        return self.module / math.cos(self.helix_angle)

    @cached_property
    def transverse_pressure_angle(self) -> float:
        """alpha_t, tan(alpha_t) = tan(alpha_n) / cos(beta) [rad]."""
        return math.atan(math.tan(self.pressure_angle) / math.cos(self.helix_angle))

    @cached_property
    def base_helix_angle(self) -> float:
        """beta_b, tan(beta_b) = tan(beta) cos(alpha_t) [rad]."""
        return math.atan(math.tan(self.helix_angle) * math.cos(self.transverse_pressure_angle))

    @cached_property
    def pitch_radius(self) -> tuple[float, float]:
        """Reference radii r = m_t z / 2 [m]."""
        return tuple(0.5 * self.transverse_module * z for z in self.teeth)

    @cached_property
    def base_radius(self) -> tuple[float, float]:
        """Base radii r_b = r cos(alpha_t) [m]."""
        c = math.cos(self.transverse_pressure_angle)
        return tuple(r * c for r in self.pitch_radius)

    @cached_property
    def tip_radius(self) -> tuple[float, float]:
        """Tip radii r_a = r + m_n (h_a* + x) [m]."""
        return tuple(r + self.module * (self.addendum_coefficient + x)
                     for r, x in zip(self.pitch_radius, self.profile_shift, strict=True))

    @cached_property
    def root_radius(self) -> tuple[float, float]:
        """Root radii r_f = r - m_n (h_f* - x) [m]."""
        return tuple(r - self.module * (self.dedendum_coefficient - x)
                     for r, x in zip(self.pitch_radius, self.profile_shift, strict=True))

    @cached_property
    def base_pitch(self) -> float:
        """Transverse base pitch p_bt = 2 pi r_b1 / z1 [m]."""
        return 2.0 * math.pi * self.base_radius[0] / self.teeth[0]

    @cached_property
    def operating_pressure_angle(self) -> float:
        """Operating transverse pressure angle a', cos(a') = (r_b1 + r_b2) / a [rad]."""
        c = sum(self.base_radius) / self.centre_distance
        if c >= 1.0:
            raise GearGeometryError(
                f"centre_distance = {self.centre_distance!r} m is below the sum of the base "
                f"radii {sum(self.base_radius)!r} m")
        return math.acos(c)

    @cached_property
    def line_of_action_length(self) -> float:
        """``|T1T2| = a sin(a')`` [m]."""
        return self.centre_distance * math.sin(self.operating_pressure_angle)

    @cached_property
    def transverse_tooth_thickness(self) -> tuple[float, float]:
        """Transverse arc tooth thickness on the reference circle [m].

        ``s_t = m_t (pi / 2 + 2 x tan(alpha_n)) = m_t pi / 2 + 2 x m_n tan(alpha_t)``.
        """
        return tuple(0.5 * math.pi * self.transverse_module
                     + 2.0 * x * self.module * math.tan(self.transverse_pressure_angle)
                     for x in self.profile_shift)

    def half_tooth_angle(self, gear: int, radius: float) -> float:
        """Half angular thickness psi(r) of the involute tooth of wheel ``gear`` at ``radius``.

        ``psi = s_t / (2 r) + inv(alpha_t) - inv(alpha_r)``, ``cos(alpha_r) = r_b / r`` (r >= r_b).
        """
        rb = self.base_radius[gear]
        alpha_r = math.acos(min(1.0, rb / radius))
        return (self.transverse_tooth_thickness[gear] / (2.0 * self.pitch_radius[gear])
                + involute(self.transverse_pressure_angle) - involute(alpha_r))

    # ------------------------------------------------------------------ path of contact
    @cached_property
    def path_of_contact(self) -> tuple[float, float]:
        """(xi_A, xi_E): start (gear tip) and end (pinion tip) of contact on T1T2 [m]."""
        (ra1, ra2), (rb1, rb2) = self.tip_radius, self.base_radius
        xi_e = math.sqrt(ra1**2 - rb1**2)
        xi_a = self.line_of_action_length - math.sqrt(ra2**2 - rb2**2)
        return xi_a, xi_e

    @cached_property
    def transverse_contact_ratio(self) -> float:
        """epsilon_alpha = (xi_E - xi_A) / p_bt [-]."""
        xi_a, xi_e = self.path_of_contact
        return (xi_e - xi_a) / self.base_pitch

    @property
    def contact_width(self) -> float:
        """Common face width b = min(b1, b2) [m] (both centred on z = 0)."""
        return min(self.face_width)

    @cached_property
    def overlap_ratio(self) -> float:
        """epsilon_beta = b tan(beta_b) / p_bt [-]."""
        return self.contact_width * math.tan(self.base_helix_angle) / self.base_pitch

    @property
    def total_contact_ratio(self) -> float:
        """epsilon_gamma = epsilon_alpha + epsilon_beta [-]."""
        return self.transverse_contact_ratio + self.overlap_ratio

    def contact_radius(self, xi: float) -> tuple[float, float]:
        """Radii of the contact point on the pinion and on the gear at abscissa xi [m]."""
        rb1, rb2 = self.base_radius
        return math.hypot(rb1, xi), math.hypot(rb2, self.line_of_action_length - xi)

    # ------------------------------------------------------------------ checks
    @cached_property
    def backlash(self) -> float:
        """Transverse backlash along the line of action at the operating centre distance [m].

        ``j = p_w - s_w1 - s_w2`` on the operating pitch circles (arc), times cos(a'), with
        ``s_w = 2 r_w psi(r_w)``; negative means the teeth overlap.
        """
        aw = self.operating_pressure_angle
        rw = [rb / math.cos(aw) for rb in self.base_radius]
        pw = 2.0 * math.pi * rw[0] / self.teeth[0]
        sw = [2.0 * r * self.half_tooth_angle(i, r) for i, r in enumerate(rw)]
        return (pw - sw[0] - sw[1]) * math.cos(aw)

    @cached_property
    def tip_clearance(self) -> tuple[float, float]:
        """(a - r_a1 - r_f2, a - r_a2 - r_f1): bottom clearance of the pinion and gear tips [m]."""
        (ra1, ra2), (rf1, rf2) = self.tip_radius, self.root_radius
        a = self.centre_distance
        return a - ra1 - rf2, a - ra2 - rf1

    @cached_property
    def form_abscissa(self) -> tuple[float, float]:
        """Where the generated involute of each wheel starts, as a distance from its own
        tangency point along the line of action (T1 for the pinion, T2 for the gear) [m].

        The generating rack's straight flank reaches h_a* m_n below its reference line: the
        involute is generated down to ``r sin(alpha_t) - m_n (h_a* - x) / sin(alpha_t)`` from T
        (rack-gear line of action). Negative means undercut.
        """
        at = self.transverse_pressure_angle
        return tuple(r * math.sin(at) - self.module * (self.addendum_coefficient - x)
                     / math.sin(at)
                     for r, x in zip(self.pitch_radius, self.profile_shift, strict=True))

    def check(self) -> None:
        """Raise :class:`GearGeometryError` naming the values if the pair cannot mesh."""
        _ = self.operating_pressure_angle  # raises below the sum of the base radii
        (c1, c2) = self.tip_clearance
        for name, c, other in (("pinion", c1, "gear"), ("gear", c2, "pinion")):
            if c <= 1e-9 * self.module:
                what = (f"cut {-c * 1e3:.3f} mm into" if c < -1e-9 * self.module
                        else "touch")
                raise GearGeometryError(
                    f"the {name} tips {what} the {other}'s root circle "
                    f"(centre distance {self.centre_distance * 1e3:.3f} mm, tip radius "
                    f"{self.tip_radius[0 if name == 'pinion' else 1] * 1e3:.3f} mm, root radius "
                    f"{self.root_radius[1 if name == 'pinion' else 0] * 1e3:.3f} mm): no bottom "
                    f"clearance")
        if self.backlash < -1e-9 * self.module:
            raise GearGeometryError(
                f"the teeth overlap by {-self.backlash * 1e6:.2f} um along the line of action at "
                f"centre distance {self.centre_distance * 1e3:.3f} mm: increase it or reduce the "
                f"profile shifts {self.profile_shift}")
        for i, name in enumerate(("pinion", "gear")):
            if self.form_abscissa[i] < 0.0:
                x_min = self.addendum_coefficient - (
                    self.pitch_radius[i] * math.sin(self.transverse_pressure_angle) ** 2
                    / self.module)
                raise GearGeometryError(
                    f"the {name} (z = {self.teeth[i]}) is undercut by the generating rack: "
                    f"profile shift {self.profile_shift[i]} < {x_min:.4f}")
        xi_a, xi_e = self.path_of_contact
        t1t2 = self.line_of_action_length
        if xi_a < self.form_abscissa[0]:
            raise GearGeometryError(
                f"tip-to-root interference: the gear tips reach xi_A = {xi_a * 1e3:.3f} mm on "
                f"the line of action, below the pinion's involute, which starts at "
                f"{self.form_abscissa[0] * 1e3:.3f} mm from T1")
        if t1t2 - xi_e < self.form_abscissa[1]:
            raise GearGeometryError(
                f"tip-to-root interference: the pinion tips reach {(t1t2 - xi_e) * 1e3:.3f} mm "
                f"from T2, below the gear's involute, which starts at "
                f"{self.form_abscissa[1] * 1e3:.3f} mm from T2")
        if self.transverse_contact_ratio + self.overlap_ratio < 1.0:
            raise GearGeometryError(
                f"total contact ratio {self.total_contact_ratio:.4f} < 1: the mesh loses "
                "contact between tooth pairs")

    def nominal_line_load(self, torque: float) -> float:
        """Mean load per unit contact length for a pinion torque [N/m].

        ``W = T / r_b1`` (transverse) over the mean total contact length
        ``epsilon_alpha b / cos(beta_b)``, normal load ``W / cos(beta_b)``.
        """
        cb = math.cos(self.base_helix_angle)
        w = abs(torque) / self.base_radius[0] / cb
        return w / (self.transverse_contact_ratio * self.contact_width / cb)

    def summary(self) -> str:
        """A few lines with the derived geometry (mm, deg)."""
        xi_a, xi_e = self.path_of_contact
        return "\n".join([
            f"teeth {self.teeth}, m_n {self.module * 1e3:g} mm, alpha_n "
            f"{math.degrees(self.pressure_angle):g} deg, beta {math.degrees(self.helix_angle):g}"
            f" deg, x {self.profile_shift}",
            "pitch radii " + ", ".join(f"{r * 1e3:.3f}" for r in self.pitch_radius)
            + " mm; base " + ", ".join(f"{r * 1e3:.3f}" for r in self.base_radius)
            + " mm; tip " + ", ".join(f"{r * 1e3:.3f}" for r in self.tip_radius)
            + " mm; root " + ", ".join(f"{r * 1e3:.3f}" for r in self.root_radius) + " mm",
            f"operating pressure angle {math.degrees(self.operating_pressure_angle):.4f} deg, "
            f"backlash {self.backlash * 1e6:.2f} um, tip clearances "
            + ", ".join(f"{c * 1e3:.3f}" for c in self.tip_clearance) + " mm",
            f"path of contact xi_A {xi_a * 1e3:.3f} mm .. xi_E {xi_e * 1e3:.3f} mm of "
            f"|T1T2| {self.line_of_action_length * 1e3:.3f} mm; base pitch "
            f"{self.base_pitch * 1e3:.4f} mm",
            f"contact ratios: transverse {self.transverse_contact_ratio:.4f}, overlap "
            f"{self.overlap_ratio:.4f}, total {self.total_contact_ratio:.4f}",
        ])
