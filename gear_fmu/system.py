"""The two-shaft gear system of the paper (Fig. 1, Tables 1-2): layout, DOF maps, assembly.

Layout
------
Two parallel shafts along z, both spanning ``z in [-L/2, L/2]``; the pinion shaft's axis passes
through O1 = (0, 0), the gear shaft's through O2 = (a, 0) (a = centre distance, s from O1 to O2).
Each shaft has ``n_elements`` (even) equal Timoshenko elements; the pinion and the gear sit on the
mid node (z = 0, symmetric system), the bearings at the end nodes:

=========  ===========  =========
bearing    shaft        z
=========  ===========  =========
1          pinion       -L/2
2          pinion       +L/2
3          gear         -L/2
4          gear         +L/2
=========  ===========  =========

Node numbering: pinion shaft nodes ``0..n``, gear shaft nodes ``n+1..2n+1`` (both from z = -L/2).

Boundary conditions (choices, documented)
-----------------------------------------
* Torsion (default, :class:`gear_fmu.drivetrain.Drivetrain` ``()``): the torsion DOF at the
  gear shaft's output end (z = +L/2) is clamped, i.e. the output drives a load of infinite
  inertia; the resisting torque is the reaction there. The rigid-body rotation of both shafts
  is imposed kinematics (pinion angle ``omega t``) and the ``theta`` DOFs are the small elastic
  rotations on top of it. The input torque acts on the pinion shaft's torsion DOF at its input
  end (z = -L/2). A motor inertia at the input and a load inertia at the output (rigid or
  behind couplings, extra DOFs after the node DOFs) are set by ``drivetrain``
  (:mod:`gear_fmu.drivetrain`).
* Axial: one axial spring (thrust bearing) of stiffness ``axial_stiffness`` (default 1e9 N/m, not
  given in the paper) on ``w`` at the z = -L/2 node of each shaft.
* Radial (u, v): no support in the structural matrices; the four bearings enter from outside
  (affine laws ``F0 - Kb X - Cb Xdot``). Bending rotations are free at the bearings.

Gear bodies (choice, documented)
--------------------------------
Rigid discs on the mid nodes with the Table 1 masses (pinion 2 kg, gear 74 kg). Unless given
(``GearBody.polar_inertia``, ``diametral_inertia``), their inertias are those of a steel
annulus (rho = 7800 kg/m^3) of face width b and outer radius equal to the transverse pitch
radius r = m z / (2 cos beta), the bore radius r_i chosen so that the annulus has the given
mass: ``r_i^2 = r^2 - M / (rho pi b)``. Spur case: pinion r = 52 mm, r_i = 32.7 mm (close to
the 35 mm shaft radius), Ip = 3.77e-3 kg m^2, Id = 2.30e-3 kg m^2; gear r = 314 mm, r_i =
152 mm, Ip = 4.50 kg m^2, Id = 2.26 kg m^2 (see :func:`annulus_inertias`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bearing_fmu.blas_threads import one_blas_thread
from gear_fmu.dofs import DOF_PER_NODE, THETA, U, V, W, dof
from gear_fmu.drivetrain import Drivetrain
from gear_fmu.timoshenko import HollowSection, disc_matrices, timoshenko_element

__all__ = [
    "GearBody",
    "GearShaftSystem",
    "Shaft",
    "annulus_inertias",
]


@dataclass(frozen=True)
class Shaft:
    """One shaft: hollow section, length, number of equal elements (even)."""

    section: HollowSection
    length: float
    n_elements: int = 8

    def __post_init__(self) -> None:
        if not (math.isfinite(self.length) and self.length > 0.0):
            raise ValueError(f"shaft length = {self.length!r} m must be finite and > 0")
        if self.n_elements < 2 or self.n_elements % 2:
            raise ValueError(
                f"n_elements = {self.n_elements!r}: must be even and >= 2 (a mid node carries "
                "the gear)"
            )

    @property
    def mass(self) -> float:
        """Shaft mass rho A L [kg]."""
        return self.section.mass_per_length * self.length

    @property
    def node_z(self) -> np.ndarray:
        """Axial node positions [m], from -L/2 to +L/2."""
        return np.linspace(-0.5 * self.length, 0.5 * self.length, self.n_elements + 1)


def annulus_inertias(
    mass: float, outer_radius: float, width: float, density: float = 7800.0
) -> tuple[float, float, float]:
    """Bore radius and inertias of a uniform annulus of given mass, outer radius and width.

    Parameters
    ----------
    mass : float
        [kg]
    outer_radius, width : float
        [m]
    density : float
        [kg/m^3]

    Returns
    -------
    (inner_radius, diametral_inertia, polar_inertia) : [m], [kg m^2], [kg m^2]
        ``Ip = M (r^2 + r_i^2) / 2``, ``Id = M (r^2 + r_i^2) / 4 + M b^2 / 12``.

    Raises
    ------
    ValueError
        If a full disc of that size is lighter than ``mass``.
    """
    full = density * math.pi * outer_radius**2 * width
    if not 0.0 < mass <= full:
        raise ValueError(
            f"gear mass {mass!r} kg must be in (0, {full:.4g}] kg, the mass of a full steel "
            f"disc of radius {outer_radius!r} m and width {width!r} m"
        )
    ri2 = outer_radius**2 - mass / (density * math.pi * width)
    ri2 = max(ri2, 0.0)
    ip = 0.5 * mass * (outer_radius**2 + ri2)
    idiam = 0.25 * mass * (outer_radius**2 + ri2) + mass * width**2 / 12.0
    return math.sqrt(ri2), idiam, ip


@dataclass(frozen=True)
class GearBody:
    """Rigid gear body on the mid node of its shaft.

    Inertias [kg m^2]: ``polar_inertia`` and ``diametral_inertia`` when given (> 0), else those
    of :func:`annulus_inertias` (0 = derived).
    """

    mass: float
    pitch_radius: float
    face_width: float
    density: float = 7800.0
    polar_inertia: float = 0.0
    diametral_inertia: float = 0.0

    def __post_init__(self) -> None:
        for name in ("polar_inertia", "diametral_inertia"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0.0):
                raise ValueError(f"gear {name} = {v!r} kg.m^2 must be finite and >= 0 "
                                 "(0 = derived from the mass)")

    @property
    def inertias(self) -> tuple[float, float, float]:
        """(bore radius [m], diametral inertia [kg m^2], polar inertia [kg m^2])."""
        ri, idiam, ip = annulus_inertias(self.mass, self.pitch_radius, self.face_width,
                                         self.density) if not (
            self.polar_inertia and self.diametral_inertia) else (math.nan, 0.0, 0.0)
        return (ri, self.diametral_inertia or idiam, self.polar_inertia or ip)


@dataclass
class GearShaftSystem:
    """Assembled structural model of the two-shaft gear system (paper Eq. 9, K_shaft and M).

    The attributes below are all built by :meth:`build`.

    Attributes
    ----------
    n_dof : int
        Total DOFs (6 per node, including the clamped one, then the drivetrain's motor and
        load DOFs, :mod:`gear_fmu.drivetrain`).
    mass, stiffness : (n_dof, n_dof) arrays
        Global M and K_shaft (shafts, discs, axial springs, motor and load inertias and
        couplings) [SI].
    coupling_damping : (n_dof, n_dof) array
        Viscous damping of the drivetrain couplings [N m s/rad].
    free : int array
        DOFs kept (all but the clamped output torsion DOF, if clamped).
    bearing_nodes : (4,) int
        Nodes of bearings 1..4.
    bearing_dofs : (4, 2) int
        Global (u, v) DOFs of bearings 1..4.
    gear_nodes : (2,) int
        Pinion and gear nodes.
    gear_dofs : (12,) int
        Pinion node 6 DOFs then gear node 6 DOFs (the mesh element's q12).
    input_dof, output_dof : int
        Pinion shaft torsion at z = -L/2; gear shaft torsion at z = +L/2 (clamped by default).
    torque_dof, load_dof : int, int or None
        Where the input torque acts (the motor DOF behind a coupling, else ``input_dof``);
        where the resisting torque acts (None when the output is clamped).
    static_ground : float
        Stiffness [N m/rad] of the spring on ``load_dof`` that fixes the free torsional
        rotation in static solutions (0 when the output is clamped).
    shaft_masses : (2,) float
        Shaft + gear mass per shaft [kg] (the M of Eq. 10).

    Examples
    --------
    Two solid steel shafts of 8 elements (the paper's system:
    :func:`fmu_src.examples.paper_system`):

    >>> steel = dict(young=210e9, poisson=0.3, density=7800.0)
    >>> shaft = Shaft(HollowSection(0.05, 0.0, **steel), 0.2, 8)
    >>> gears = (GearBody(1.0, 0.04, 0.03), GearBody(4.0, 0.08, 0.03))
    >>> sys_ = GearShaftSystem((shaft, shaft), gears, centre_distance=0.12, teeth=(20, 40))
    >>> sys_.n_dof, sys_.free.size, sys_.gear_nodes.tolist()
    (108, 107, [4, 13])
    """

    shafts: tuple[Shaft, Shaft]
    gears: tuple[GearBody, GearBody]
    centre_distance: float
    teeth: tuple[int, int]
    axial_stiffness: float = 1e9
    helix_angle_deg: float = 0.0
    drivetrain: Drivetrain = field(default_factory=Drivetrain)
    n_dof: int = field(init=False)
    mass: np.ndarray = field(init=False, repr=False)
    stiffness: np.ndarray = field(init=False, repr=False)
    free: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.axial_stiffness) and self.axial_stiffness > 0.0):
            raise ValueError(f"axial_stiffness = {self.axial_stiffness!r} N/m must be > 0")
        if not (math.isfinite(self.centre_distance) and self.centre_distance > 0.0):
            raise ValueError(f"centre_distance = {self.centre_distance!r} m must be > 0")
        self.build()

    # ------------------------------------------------------------------ layout
    @property
    def shaft_first_node(self) -> tuple[int, int]:
        """First node of each shaft."""
        return 0, self.shafts[0].n_elements + 1

    @property
    def n_nodes(self) -> int:
        return sum(s.n_elements + 1 for s in self.shafts)

    @one_blas_thread
    def build(self) -> None:
        """Assemble M and K_shaft of Eq. (9) (shaft elements, gear discs, thrust springs) and
        the DOF maps."""
        n_nodes = self.n_nodes
        self.n_dof = DOF_PER_NODE * n_nodes
        m = np.zeros((self.n_dof, self.n_dof))
        k = np.zeros((self.n_dof, self.n_dof))
        firsts = self.shaft_first_node
        bearing_nodes, gear_nodes = [], []
        for shaft, first, gear in zip(self.shafts, firsts, self.gears, strict=True):
            le = shaft.length / shaft.n_elements
            ke, me = timoshenko_element(shaft.section, le)
            for e in range(shaft.n_elements):
                idx = np.arange(DOF_PER_NODE * (first + e), DOF_PER_NODE * (first + e + 2))
                k[np.ix_(idx, idx)] += ke
                m[np.ix_(idx, idx)] += me
            mid = first + shaft.n_elements // 2
            gear_nodes.append(mid)
            _, idiam, ip = gear.inertias
            idx = np.arange(DOF_PER_NODE * mid, DOF_PER_NODE * (mid + 1))
            m[np.ix_(idx, idx)] += disc_matrices(gear.mass, idiam, ip)
            bearing_nodes += [first, first + shaft.n_elements]
            k[dof(first, W), dof(first, W)] += self.axial_stiffness
        self.mass = m
        self.stiffness = k
        self.bearing_nodes = np.array(bearing_nodes)
        self.bearing_dofs = np.array([[dof(n, U), dof(n, V)] for n in bearing_nodes])
        self.gear_nodes = np.array(gear_nodes)
        self.gear_dofs = np.concatenate(
            [np.arange(DOF_PER_NODE * n, DOF_PER_NODE * (n + 1)) for n in gear_nodes]
        )
        self.input_dof = dof(firsts[0], THETA)
        self.output_dof = dof(firsts[1] + self.shafts[1].n_elements, THETA)
        self._drivetrain()
        clamped = [self.output_dof] if self.drivetrain.clamped else []
        self.free = np.setdiff1d(np.arange(self.n_dof), clamped)
        self.shaft_masses = np.array(
            [s.mass + g.mass for s, g in zip(self.shafts, self.gears, strict=True)]
        )

    def _drivetrain(self) -> None:
        """Motor and load inertias and couplings (:mod:`gear_fmu.drivetrain`)."""
        dt = self.drivetrain
        n0 = self.n_dof
        n = n0 + dt.n_extra
        m = np.zeros((n, n))
        k = np.zeros((n, n))
        m[:n0, :n0] = self.mass
        k[:n0, :n0] = self.stiffness
        c = np.zeros((n, n))
        nxt = n0
        self.torque_dof = self.input_dof
        self.load_dof = None
        self.extra_dofs = {}
        pairs = [("motor", self.input_dof, dt.motor_inertia, dt.motor_coupling_stiffness,
                  dt.motor_coupling_damping)]
        if not dt.clamped:
            pairs.append(("load", self.output_dof, dt.load_inertia, dt.load_coupling_stiffness,
                          dt.load_coupling_damping))
        for name, end, inertia, kc, cc in pairs:
            at = end
            if kc > 0.0:
                at = nxt
                nxt += 1
                self.extra_dofs[name] = at
                idx = [end, at]
                k[np.ix_(idx, idx)] += kc * np.array([[1.0, -1.0], [-1.0, 1.0]])
                c[np.ix_(idx, idx)] += cc * np.array([[1.0, -1.0], [-1.0, 1.0]])
            m[at, at] += inertia
            if name == "motor":
                self.torque_dof = at
            else:
                self.load_dof = at
        self.n_dof = n
        self.mass = m
        self.stiffness = k
        self.coupling_damping = c
        # static ground on the load: the torsional stiffness scale of the gear shaft
        self.static_ground = 0.0 if dt.clamped else float(
            np.max(np.diag(k)[self.dof_kind() == 1]))

    # ------------------------------------------------------------------ reduced space
    @property
    def reduced_index(self) -> np.ndarray:
        """Map full DOF -> position in the free (reduced) vector, -1 for the clamped DOF."""
        r = -np.ones(self.n_dof, dtype=int)
        r[self.free] = np.arange(self.free.size)
        return r

    def reduce(self, a: np.ndarray) -> np.ndarray:
        """Restrict a full vector or matrix to the free DOFs."""
        a = np.asarray(a)
        if a.ndim == 1:
            return a[self.free]
        return a[np.ix_(self.free, self.free)]

    def expand(self, x: np.ndarray) -> np.ndarray:
        """Full vector from a free-DOF vector (zero on the clamped DOF)."""
        out = np.zeros(self.n_dof)
        out[self.free] = x
        return out

    def dof_kind(self) -> np.ndarray:
        """Per full DOF: 0 bending (u, v, phi, psi), 1 torsion (theta, motor, load), 2 axial
        (w)."""
        n_node = DOF_PER_NODE * self.n_nodes
        local = np.arange(n_node) % DOF_PER_NODE
        kind = np.ones(self.n_dof, dtype=int)  # the drivetrain DOFs are torsion
        kind[:n_node] = 0
        kind[:n_node][local == THETA] = 1
        kind[:n_node][local == W] = 2
        return kind

    def node_positions(self) -> np.ndarray:
        """(n_nodes, 3) node coordinates (s, t, z) [m]."""
        out = []
        for shaft, s0 in zip(self.shafts, (0.0, self.centre_distance), strict=True):
            for z in shaft.node_z:
                out.append((s0, 0.0, z))
        return np.array(out)
