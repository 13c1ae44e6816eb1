"""The structure of a gear train (paper Eq. 9, K_shaft and M): nodes, DOF maps, assembly.

Built from a :class:`gear_fmu.layout.Layout`, the one source of the topology: nothing here
counts shafts, gears, meshes or bearings.

Nodes
-----
Each shaft gets nodes at its ends, at its segment ends, at every gear, bearing and disc on it
and where the drive's torques act; each interval between two such places is cut into equal
Timoshenko elements no longer than the shaft's ``element_length``. Nodes are numbered shaft by
shaft (the layout's order), from each shaft's start; every node carries the six DOFs of
:mod:`gear_fmu.dofs`, the drivetrain's motor and load DOFs follow (:mod:`gear_fmu.drivetrain`).
A node's global position is its shaft's axis (:attr:`gear_fmu.layout.Layout.shaft_centres`)
at ``z = offset + position``.

Boundary conditions (choices, documented)
-----------------------------------------
* Torsion (:class:`gear_fmu.drivetrain.Drivetrain` ``()``): the torsion DOF at the output
  position (``drive.output_position`` of ``drive.output_shaft``, default its end) is clamped,
  i.e. the output drives a load of infinite inertia; the resisting torque is the reaction
  there. The rigid-body rotations of the shafts are imposed kinematics (the input shaft at
  ``omega t``, the others through the gear ratios) and the ``theta`` DOFs are the small
  elastic rotations on top of them. The input torque acts on the input shaft's torsion DOF at
  ``drive.input_position`` (default its start). A motor inertia at the input and a load
  inertia at the output (rigid or behind couplings, extra DOFs after the node DOFs) are set by
  the drivetrain.
* Axial: one axial spring (thrust bearing) of stiffness ``axial_stiffness`` (default 1e9 N/m,
  not given in the paper) on ``w`` at the first bearing (lowest position) of each shaft.
* Radial (u, v): no support in the structural matrices; the bearings enter from outside
  (affine laws ``F0 - Kb X - Cb Xdot`` at their nodes). Bending rotations are free there.

Gear bodies and discs (choice, documented)
------------------------------------------
Rigid discs on their nodes. Unless given (``polar_inertia``, ``diametral_inertia`` > 0), a
gear's inertias are those of an annulus of its shaft's density, of face width b and outer
radius equal to the transverse pitch radius r = m z / (2 cos beta), the bore radius r_i chosen
so that the annulus has the given mass: ``r_i^2 = r^2 - M / (rho pi b)``. Paper's spur case:
pinion r = 52 mm, r_i = 32.7 mm (close to the 35 mm shaft radius), Ip = 3.77e-3 kg m^2,
Id = 2.30e-3 kg m^2; gear r = 314 mm, r_i = 152 mm, Ip = 4.50 kg m^2, Id = 2.26 kg m^2 (see
:func:`annulus_inertias`). A disc's inertias are as given.

Gyroscopic terms (not in the paper)
-----------------------------------
Each shaft's elements and the gears and discs on it spin with the shaft
(:func:`gear_fmu.timoshenko.timoshenko_gyroscopic`, :func:`gear_fmu.timoshenko.disc_gyroscopic`):
``G_i`` per unit spin of shaft i (``GearShaftSystem.shaft_gyroscopic``), and
``G(Omega) = sum_i Omega_i G_i`` with each shaft's signed speed about +z
(:meth:`GearShaftSystem.gyroscopic`).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from bearing_fmu.blas_threads import one_blas_thread
from gear_fmu.dofs import DOF_PER_NODE, THETA, U, V, W, dof
from gear_fmu.drivetrain import Drivetrain
from gear_fmu.layout import GearSpec, Layout, ShaftSpec
from gear_fmu.timoshenko import (
    disc_gyroscopic,
    disc_matrices,
    timoshenko_element,
    timoshenko_gyroscopic,
)

__all__ = ["GearShaftSystem", "Unbalances", "annulus_inertias", "gear_inertias"]


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
class Unbalances:
    """The mass unbalances of a train (Eq. 10), one entry per unbalanced gear or disc.

    ``node`` (nu,) the body's node; ``me`` (nu,) mass times eccentricity [kg m]; ``shaft``
    (nu,) the index of its shaft; ``phase`` (nu,) its angle at t = 0 [rad]."""

    node: np.ndarray
    me: np.ndarray
    shaft: np.ndarray
    phase: np.ndarray

    @property
    def count(self) -> int:
        return int(self.node.size)


def _breakpoints(layout: Layout, shaft: ShaftSpec) -> list[float]:
    """Where a shaft must have nodes [m from its start], sorted, merged within 1e-9 m."""
    places = [*shaft.breaks]
    for items in (layout.gears, layout.bearings, layout.discs):
        places += [it.position for it in items if it.shaft == shaft.name]
    if layout.drive.input_shaft == shaft.name:
        places.append(layout.input_position)
    if layout.drive.output_shaft == shaft.name:
        places.append(layout.output_position)
    out: list[float] = []
    for p in sorted(min(max(p, 0.0), shaft.length) for p in places):
        if not out or p - out[-1] > 1e-9:
            out.append(p)
    return out


def gear_inertias(gear: GearSpec, density: float) -> tuple[float, float]:
    """``(diametral, polar)`` inertia of a gear body [kg m^2]: as given, or those of
    :func:`annulus_inertias` with the transverse pitch radius (module docstring)."""
    if gear.polar_inertia and gear.diametral_inertia:
        return gear.diametral_inertia, gear.polar_inertia
    radius = gear.module * gear.teeth / (2.0 * math.cos(gear.helix_angle))
    _, idiam, ip = annulus_inertias(gear.mass, radius, gear.face_width, density)
    return gear.diametral_inertia or idiam, gear.polar_inertia or ip


@dataclass
class GearShaftSystem:
    """Assembled structural model of a gear train (paper Eq. 9, K_shaft and M).

    The attributes below are all built from ``layout`` on construction.

    Attributes
    ----------
    n_dof : int
        Total DOFs (6 per node, including a clamped one, then the drivetrain's motor and load
        DOFs, :mod:`gear_fmu.drivetrain`).
    mass, stiffness : (n_dof, n_dof) arrays
        Global M and K_shaft (shafts, gear bodies, discs, axial springs, motor and load
        inertias and couplings) [SI].
    coupling_damping : (n_dof, n_dof) array
        Viscous damping of the drivetrain couplings [N m s/rad].
    free : int array
        DOFs kept (all but the clamped output torsion DOF, if clamped).
    shaft_nodes : list of int arrays
        The nodes of each shaft, from its start.
    node_shaft, node_position : (n_nodes,) arrays
        Each node's shaft (index) and its position from the shaft's start [m].
    gear_nodes, bearing_nodes, disc_nodes : int arrays
        The node of each gear, bearing and disc (layout order).
    mesh_nodes : (n_meshes, 2) int
        The driver's and the driven gear's node of each mesh
        (:attr:`gear_fmu.layout.Layout.drivers`).
    bearing_dofs : (nb, 2) int
        Global (u, v) DOFs of each bearing.
    input_dof, output_dof : int
        Torsion DOF of the input position; of the output position (clamped by default).
    torque_dof, load_dof : int, int or None
        Where the input torque acts (the motor DOF behind a coupling, else ``input_dof``);
        where the resisting torque acts (None when the output is clamped).
    static_ground : float
        Stiffness [N m/rad] of the spring on ``load_dof`` that fixes the free torsional
        rotation in static solutions (0 when the output is clamped).
    shaft_masses : (n_shafts,) float
        Mass of each shaft with everything on it [kg].
    unbalances : Unbalances
        The unbalanced bodies (Eq. 10).
    shaft_gyroscopic : (n_shafts, n_dof, n_dof) array
        Gyroscopic matrix of each shaft with its gears and discs, per unit spin [kg m^2]
        (module docstring).

    Examples
    --------
    The paper's system (:func:`fmu_src.examples.paper_system`): two shafts of 8 elements,
    the gears on their mid nodes, the bearings at the ends:

    >>> from fmu_src.examples import paper_system
    >>> sys_ = paper_system()
    >>> sys_.n_dof, sys_.free.size, sys_.gear_nodes.tolist(), sys_.bearing_nodes.tolist()
    (108, 107, [4, 13], [0, 8, 9, 17])
    """

    layout: Layout
    n_dof: int = field(init=False)
    mass: np.ndarray = field(init=False, repr=False)
    stiffness: np.ndarray = field(init=False, repr=False)
    free: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.build()

    # ------------------------------------------------------------------ layout
    @property
    def drivetrain(self) -> Drivetrain:
        return self.layout.drive.drivetrain

    @property
    def n_nodes(self) -> int:
        return int(self.node_shaft.size)

    def _node_at(self, shaft: str, position: float) -> int:
        i = self.layout.shaft_index[shaft]
        nodes = self.shaft_nodes[i]
        k = int(np.argmin(np.abs(self.node_position[nodes] - position)))
        return int(nodes[k])

    @one_blas_thread
    def build(self) -> None:
        """Assemble M and K_shaft of Eq. (9) (shaft elements, gear bodies, discs, thrust
        springs) and the DOF maps."""
        lay = self.layout
        shaft_nodes, node_shaft, node_pos, elements = [], [], [], []
        for i, shaft in enumerate(lay.shafts):
            first = len(node_shaft)
            points = _breakpoints(lay, shaft)
            pos = [points[0]]
            for a, b in itertools.pairwise(points):
                n = max(1, math.ceil((b - a) / shaft.element_length - 1e-9))
                le = (b - a) / n
                seg = shaft.segment_at(a, b)
                for k in range(n):
                    elements.append((len(pos) - 1 + first, le, i, seg))
                    pos.append(a + (b - a) * (k + 1) / n)
            shaft_nodes.append(np.arange(first, first + len(pos)))
            node_shaft += [i] * len(pos)
            node_pos += pos
        self.shaft_nodes = shaft_nodes
        self.node_shaft = np.array(node_shaft, dtype=int)
        self.node_position = np.array(node_pos)
        n_dof = DOF_PER_NODE * len(node_shaft)
        m = np.zeros((n_dof, n_dof))
        k = np.zeros((n_dof, n_dof))
        gyro = np.zeros((len(lay.shafts), n_dof, n_dof))
        cache: dict = {}
        for node, le, i, seg in elements:
            key = (i, seg, le)
            if key not in cache:
                section = lay.shafts[i].section(seg)
                cache[key] = (*timoshenko_element(section, le),
                              timoshenko_gyroscopic(section, le))
            ke, me, ge = cache[key]
            idx = np.arange(DOF_PER_NODE * node, DOF_PER_NODE * (node + 2))
            k[np.ix_(idx, idx)] += ke
            m[np.ix_(idx, idx)] += me
            gyro[i][np.ix_(idx, idx)] += ge
        self.gear_nodes = np.array([self._node_at(g.shaft, g.position) for g in lay.gears],
                                   dtype=int)
        for gear, node in zip(lay.gears, self.gear_nodes, strict=True):
            idiam, ip = gear_inertias(gear, lay.shaft(gear.shaft).density)
            idx = np.arange(DOF_PER_NODE * node, DOF_PER_NODE * (node + 1))
            m[np.ix_(idx, idx)] += disc_matrices(gear.mass, idiam, ip)
            gyro[lay.shaft_index[gear.shaft]][np.ix_(idx, idx)] += disc_gyroscopic(ip)
        self.disc_nodes = np.array([self._node_at(d.shaft, d.position) for d in lay.discs],
                                   dtype=int)
        for d, node in zip(lay.discs, self.disc_nodes, strict=True):
            idx = np.arange(DOF_PER_NODE * node, DOF_PER_NODE * (node + 1))
            m[np.ix_(idx, idx)] += disc_matrices(d.mass, d.diametral_inertia, d.polar_inertia)
            gyro[lay.shaft_index[d.shaft]][np.ix_(idx, idx)] += disc_gyroscopic(d.polar_inertia)
        self.bearing_nodes = np.array([self._node_at(b.shaft, b.position)
                                       for b in lay.bearings], dtype=int)
        self.bearing_dofs = np.array([[dof(n, U), dof(n, V)] for n in self.bearing_nodes],
                                     dtype=int).reshape(-1, 2)
        for shaft in lay.shafts:  # the thrust spring at each shaft's first bearing
            first = min((b for b in lay.bearings if b.shaft == shaft.name),
                        key=lambda b: b.position)
            node = self._node_at(shaft.name, first.position)
            k[dof(node, W), dof(node, W)] += shaft.axial_stiffness
        gear_node = dict(zip((g.name for g in lay.gears), self.gear_nodes, strict=True))
        self.mesh_nodes = np.array([[gear_node[d], gear_node[n]] for d, n in lay.drivers],
                                   dtype=int).reshape(-1, 2)
        self.n_dof = n_dof
        self.mass = m
        self.stiffness = k
        self.shaft_gyroscopic = gyro
        self.input_dof = dof(self._node_at(lay.drive.input_shaft, lay.input_position), THETA)
        self.output_dof = dof(self._node_at(lay.drive.output_shaft, lay.output_position),
                              THETA)
        self._drivetrain()
        clamped = [self.output_dof] if self.drivetrain.clamped else []
        self.free = np.setdiff1d(np.arange(self.n_dof), clamped)
        self.shaft_masses = np.array([lay.carried_mass(s.name) for s in lay.shafts])
        self.unbalances = self._unbalances()

    def _unbalances(self) -> Unbalances:
        lay = self.layout
        rows = []
        bodies = [*zip(lay.gears, self.gear_nodes, strict=True),
                  *zip(lay.discs, self.disc_nodes, strict=True)]
        for body, node in bodies:
            if body.unbalance > 0.0:
                mass = body.mass if body.unbalance_mass == "body" else lay.carried_mass(
                    body.shaft)
                rows.append((node, mass * body.unbalance, lay.shaft_index[body.shaft],
                             body.unbalance_phase))
        cols = list(zip(*rows, strict=True)) if rows else [(), (), (), ()]
        return Unbalances(np.array(cols[0], dtype=int), np.array(cols[1], dtype=float),
                          np.array(cols[2], dtype=int), np.array(cols[3], dtype=float))

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
        g = np.zeros((self.shaft_gyroscopic.shape[0], n, n))
        g[:, :n0, :n0] = self.shaft_gyroscopic
        self.shaft_gyroscopic = g
        # static ground on the load: the torsional stiffness scale of the shafts
        self.static_ground = 0.0 if dt.clamped else float(
            np.max(np.diag(k)[self.dof_kind() == 1]))

    def gyroscopic(self, speeds) -> np.ndarray:
        """``G(Omega) = sum_i Omega_i G_i`` (n_dof, n_dof) [N m s]: the gyroscopic matrix at the
        shafts' signed ``speeds`` about +z [rad/s] (:func:`gear_fmu.loads.shaft_speeds`;
        module docstring). Its term ``G(Omega) Xd`` joins ``C Xd`` in Eq. (9)."""
        w = np.asarray(speeds, dtype=float)
        if w.shape != (self.shaft_gyroscopic.shape[0],):
            raise ValueError(f"speeds: one per shaft ({self.shaft_gyroscopic.shape[0]}), "
                             f"got shape {w.shape}")
        return np.einsum("i,ijk->jk", w, self.shaft_gyroscopic)

    def rigid_rotation(self, signed_ratios) -> np.ndarray:
        """(n_dof,) the rigid-body rotation of the train per unit rotation of the input shaft
        about +z: each node's ``theta`` its shaft's ``signed_ratios`` entry (the layout's
        ratios times its directions), a motor's or a load's DOF behind a coupling that of the
        shaft it drives. ``-M u_rb dOmega/dt`` is the inertia load of a run-up on the
        ``theta`` DOFs, which are rotations on top of the imposed one (docs/equations.md
        "Run-ups")."""
        s = np.asarray(signed_ratios, dtype=float)
        lay = self.layout
        u = np.zeros(self.n_dof)
        for node, shaft in enumerate(self.node_shaft):
            u[dof(node, THETA)] = s[shaft]
        for name, shaft in (("motor", lay.drive.input_shaft), ("load", lay.drive.output_shaft)):
            if name in self.extra_dofs:
                u[self.extra_dofs[name]] = s[lay.shaft_index[shaft]]
        return u

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
        """(n_nodes, 3) node coordinates (s, t, z) [m] (module docstring)."""
        lay = self.layout
        centres = lay.shaft_centres[self.node_shaft]
        offsets = np.array([s.offset for s in lay.shafts])[self.node_shaft]
        return np.column_stack([centres, offsets + self.node_position])
