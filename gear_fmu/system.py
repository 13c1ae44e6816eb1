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
* Torsion: the torsion DOF at the gear shaft's output end (z = +L/2) is clamped, i.e. the output
  drives a load of infinite inertia; the resisting torque is the reaction there. The rigid-body
  rotation of both shafts is imposed kinematics (pinion angle ``omega t``) and the ``theta`` DOFs
  are the small elastic rotations on top of it. The input torque acts on the pinion shaft's
  torsion DOF at its input end (z = -L/2).
* Axial: one axial spring (thrust bearing) of stiffness ``axial_stiffness`` (default 1e9 N/m, not
  given in the paper) on ``w`` at the z = -L/2 node of each shaft.
* Radial (u, v): no support in the structural matrices; the four bearings enter from outside
  (affine laws ``F0 - Kb X - Cb Xdot``). Bending rotations are free at the bearings.

Gear bodies (choice, documented)
--------------------------------
Rigid discs on the mid nodes with the Table 1 masses (pinion 2 kg, gear 74 kg). Their inertias are
those of a steel annulus (rho = 7800 kg/m^3) of face width b and outer radius equal to the
transverse pitch radius r = m z / (2 cos beta), the bore radius r_i chosen so that the annulus has
the given mass: ``r_i^2 = r^2 - M / (rho pi b)``. Spur case: pinion r = 52 mm, r_i = 32.7 mm (close
to the 35 mm shaft radius), Ip = 3.77e-3 kg m^2, Id = 2.30e-3 kg m^2; gear r = 314 mm, r_i =
152 mm, Ip = 4.50 kg m^2, Id = 2.26 kg m^2 (see :func:`annulus_inertias`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .dofs import DOF_PER_NODE, THETA, U, V, W, dof
from .timoshenko import HollowSection, disc_matrices, timoshenko_element

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
    """Rigid gear body on the mid node of its shaft (inertias: :func:`annulus_inertias`)."""

    mass: float
    pitch_radius: float
    face_width: float
    density: float = 7800.0

    @property
    def inertias(self) -> tuple[float, float, float]:
        """(bore radius [m], diametral inertia [kg m^2], polar inertia [kg m^2])."""
        return annulus_inertias(self.mass, self.pitch_radius, self.face_width, self.density)


@dataclass
class GearShaftSystem:
    """Assembled structural model of the two-shaft gear system (paper Eq. 9, K_shaft and M).

    The attributes below are all built by :meth:`build`.

    Attributes
    ----------
    n_dof : int
        Total DOFs (6 per node, including the clamped one).
    mass, stiffness : (n_dof, n_dof) arrays
        Global M and K_shaft (shafts, discs, axial springs) [SI].
    free : int array
        DOFs kept (all but the clamped output torsion DOF).
    bearing_nodes : (4,) int
        Nodes of bearings 1..4.
    bearing_dofs : (4, 2) int
        Global (u, v) DOFs of bearings 1..4.
    gear_nodes : (2,) int
        Pinion and gear nodes.
    gear_dofs : (12,) int
        Pinion node 6 DOFs then gear node 6 DOFs (the mesh element's q12).
    input_dof, output_dof : int
        Pinion shaft torsion at z = -L/2; gear shaft torsion at z = +L/2 (clamped).
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
        self.free = np.setdiff1d(np.arange(self.n_dof), [self.output_dof])
        self.shaft_masses = np.array(
            [s.mass + g.mass for s, g in zip(self.shafts, self.gears, strict=True)]
        )

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
        """Per full DOF: 0 bending (u, v, phi, psi), 1 torsion (theta), 2 axial (w)."""
        local = np.arange(self.n_dof) % DOF_PER_NODE
        kind = np.zeros(self.n_dof, dtype=int)
        kind[local == THETA] = 1
        kind[local == W] = 2
        return kind

    def node_positions(self) -> np.ndarray:
        """(n_nodes, 3) node coordinates (s, t, z) [m]."""
        out = []
        for shaft, s0 in zip(self.shafts, (0.0, self.centre_distance), strict=True):
            for z in shaft.node_z:
                out.append((s0, 0.0, z))
        return np.array(out)
