"""Distributed nonlinear gear mesh element (paper Sec. 2.1, Eq. 9; Velex & Maatar 1996).

The pinion and gear nodes (6 DOFs each, :mod:`gear_fmu.dofs`) are joined by elemental springs
spread along the contact lines in the base plane (:mod:`gear_fmu.mesh.geometry` for the frames).

Contact lines (rigid-body kinematics)
-------------------------------------
At pinion angle Theta1 the contact lines in the base plane are

    xi_j(z) = xi_A + p_bt (frac(w) + j),   w = (r_b1 Theta1 - z tan(beta_b)) / p_bt,

j = 0, 1, ..., kept where ``xi_A <= xi_j < xi_E`` (a line within 1e-9 p_bt of xi_A counts as
entered, so that an entry at a step time does not depend on the round-off of t); the face width
``[-b/2, b/2]`` (common width, centred on the gear nodes) is cut into ``n_slices`` slices of
width dz, each carrying a piece of contact line of length ``dl = dz / cos(beta_b)`` at its
centre. Tooth pair ``j - floor(w)`` (the number of the pair in the order of engagement) selects
the pitch errors.

Normal approach and structure vector
------------------------------------
The flank normal in the base plane is ``n = cos(beta_b) u + sin(beta_b) e_z`` (u along the line
of action). At a contact point M the normal approach is

    delta(M) = V(M) . (q + q_err) - e(M),   V = [n; O1M x n; -n; -(O2M x n)]  (12)

(q the 12 gear-node DOFs, pinion first), so that the pinion rotation enters as
``r_b1 cos(beta_b) theta1`` and the gear rotation as ``r_b2 cos(beta_b) theta2``: a positive input
torque closes the mesh. ``q_err`` are the mounting errors expressed as rigid displacements of the
gear bodies (static offsets and tilts, plus the rotating runout of each wheel), ``e(M) >= 0`` the
tooth deviations (tip relief, crowning, lead slope, pitch errors), which open the gap.

Contact condition and outputs (Eq. 9)
-------------------------------------
A slice carries ``k(xi) dl delta`` when ``delta > 0`` and nothing otherwise (unilateral; k from
:mod:`gear_fmu.mesh.tooth_stiffness`, per unit contact length). For the current contact set::

    K_gear = sum k dl V V^T,   force on q = -sum k dl delta V = -(K_gear (q + q_err) - F_dev)

with ``F_dev = sum k dl e V`` the forcing of the deviations. :meth:`MeshElement.evaluate` returns
the force, its tangent ``-d force / d q = K_gear`` and the contact set; the structure's contact
loop (:class:`gear_fmu.structure.Structure`) iterates until the set is stable.

V is affine in the contact point: ``V = P u`` with ``u = (1, xi, z)`` and P (12, 3) fixed by
the geometry (``_structure_matrix``), since ``O1M = T1 + xi u_s + z e_z``. The kernel
computes through it: ``delta = (P^T (q + q_err)) . u - e``, the force ``-P sum k dl delta u``
and ``K_gear = P (sum k dl u u^T) P^T``, three sums per slice for the force and six moments
per contact set for the tangent instead of 12 and 144 products per slice.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from gear_fmu.mesh.geometry import GearPair
from gear_fmu.mesh.tooth_stiffness import mesh_stiffness_table

__all__ = ["MeshElement", "MeshState", "ToothDeviations", "pair_frame", "transmission_error"]


@dataclass(frozen=True)
class ToothDeviations:
    """Tooth shape deviations and mounting errors (positive deviations open the mesh) [m, rad].

    Parameters
    ----------
    tip_relief : (float, float)
        Tip relief amplitude at the tip of the pinion and of the gear [m].
    relief_length : (float, float)
        Extent of each relief along the line of action, measured from the tip contact point
        (xi_E for the pinion, xi_A for the gear) [m].
    relief_exponent : float
        1 linear, 2 parabolic relief.
    crowning : float
        Lead crowning of the pair: ``e = crowning (2 z / b)^2`` [m].
    lead_slope : float
        Helix slope deviation of the pair across the face width: ``e = lead_slope z / b`` [m].
    pitch_errors : (array, array)
        Pitch deviation of each tooth along the base normal [m], pinion (z1 values) and gear
        (z2 values), indexed by the order of engagement from Theta1 = 0 (empty = none).
    mounting : (12,) array
        Static rigid error of the gear bodies on the 12 gear-node DOFs (translations [m],
        tilts [rad]) added to q: e.g. a misalignment of the gear axis in the plane of action.
    runout : (float, float)
        Eccentricity of the pinion and of the gear on their shafts [m], turning with them.
    runout_phase : (float, float)
        Angular position of each eccentricity at t = 0 [rad].
    """

    tip_relief: tuple[float, float] = (0.0, 0.0)
    relief_length: tuple[float, float] = (0.0, 0.0)
    relief_exponent: float = 2.0
    crowning: float = 0.0
    lead_slope: float = 0.0
    pitch_errors: tuple = ((), ())
    mounting: tuple = (0.0,) * 12
    runout: tuple[float, float] = (0.0, 0.0)
    runout_phase: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        for name in ("tip_relief", "relief_length", "runout"):
            v = getattr(self, name)
            if len(v) != 2 or not all(math.isfinite(x) and x >= 0.0 for x in v):
                raise ValueError(f"{name} = {v!r}: two finite values >= 0")
        for i in range(2):
            if self.tip_relief[i] > 0.0 and self.relief_length[i] <= 0.0:
                raise ValueError(f"tip_relief[{i}] = {self.tip_relief[i]!r} m needs "
                                 f"relief_length[{i}] > 0")
        if self.relief_exponent not in (1.0, 2.0):
            raise ValueError(f"relief_exponent = {self.relief_exponent!r}: 1 (linear) or 2 "
                             "(parabolic)")
        if len(self.mounting) != 12:
            raise ValueError(f"mounting has {len(self.mounting)} entries, expected 12")


def transmission_error(base_radius, q):
    """Elastic transmission error ``r_b1 theta1 + r_b2 theta2`` [m] of the gear-node DOFs
    ``q`` (..., 12) [m, rad] (rotations about the shaft axes: DOF 5 of each node, pinion
    first), base radii ``(r_b1, r_b2)`` [m]; a number for one state, an array for several."""
    rb1, rb2 = base_radius
    if q.ndim == 1:  # one state: numbers, not 0-d arrays (the same arithmetic, faster)
        return float(rb1 * q[5] + rb2 * q[11])
    return rb1 * q[..., 5] + rb2 * q[..., 11]


def pair_frame(direction: float, turn_sign: int = 1, flip_hand: bool = False) -> np.ndarray:
    """``T`` (12, 12): a pair's own frame (module docstring: pinion at the origin turning about
    +z, gear at (a, 0), the pinion's contact line ``xi(z) = xi_0 - z tan(beta_b)``, a left-hand
    pinion) from the structure's frame, ``q_own = T q`` for the 12 DOFs (u, v, w, phi, psi,
    theta) of the pinion and gear nodes.

    ``direction`` [rad]: the line of centres from the pinion's axis to the gear's in the
    structure's s-t plane (its s' axis); ``turn_sign``: the pinion's turning direction there
    (-1: the frame is mirrored across the line of centres, ``t' -> -t'``, so that the pinion
    turns about +z' in its own frame); ``flip_hand``: mirror z (``z' -> -z'``), which turns a
    right-hand pinion into the left-hand one of the element. A mirror maps the translations as
    a vector and the rotations as a pseudo-vector (the opposite sign on the mirrored axes'
    complements): t-mirror ``diag(1, -1, 1, -1, 1, -1)``, z-mirror
    ``diag(1, 1, -1, -1, -1, 1)`` on (u, v, w, phi, psi, theta).

    >>> t = pair_frame(0.5, -1, True)
    >>> bool(np.allclose(t @ t.T, np.eye(12)))
    True
    """
    c, s = math.cos(direction), math.sin(direction)
    rot = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    node = np.zeros((6, 6))
    node[:3, :3] = rot
    node[3:, 3:] = rot
    mirror = np.ones(6)
    if turn_sign < 0:
        mirror *= (1.0, -1.0, 1.0, -1.0, 1.0, -1.0)
    if flip_hand:
        mirror *= (1.0, 1.0, -1.0, -1.0, -1.0, 1.0)
    node = mirror[:, None] * node
    out = np.zeros((12, 12))
    out[:6, :6] = node
    out[6:, 6:] = node
    return out


@dataclass
class MeshState:
    """Result of :meth:`MeshElement.evaluate` (arrays per slice are (n_lines * n_slices,))."""

    force: np.ndarray  # (12,) generalised mesh force on the gear-node DOFs [N, N m]
    stiffness: np.ndarray  # (12, 12) K_gear = -d force / d q [N/m, N, N m]
    active: np.ndarray  # bool, slice in contact
    delta: np.ndarray  # normal approach [m] (meaningful where inside)
    load: np.ndarray  # slice load [N]
    inside: np.ndarray  # bool, slice on the path of contact
    xi: np.ndarray  # abscissa on the line of action [m]
    z: np.ndarray  # axial position [m]
    total_load: float  # sum of slice loads (normal mesh force) [N]
    transmission_error: float  # r_b1 theta1 + r_b2 theta2 [m], elastic torsion of the nodes
    extra: dict = field(default_factory=dict)

    @property
    def contact_length(self) -> float:
        """Total length of contact line in contact [m] (set by evaluate in ``extra``)."""
        return self.extra.get("contact_length", float("nan"))


#: contact lines closer than this fraction of a base pitch to xi_A count as entered: a line
#: enters exactly at a step time when dt divides the mesh period (paper: 1/32), and the side of
#: that tie must not depend on the round-off of t (co-simulation vs monolithic runs)
_SNAP = 1e-9


@njit(cache=True, inline="always")
def _structure_matrix(geo, p):
    """P (12, 3) with ``V = P u``, ``u = (1, xi, z)``: the structure vector
    ``V = [n; O1M x n; -n; -(O2M x n)]`` (module docstring) of the contact point at abscissa
    ``xi`` on the line of action and axial position ``z`` [m] is affine in them, since
    ``O1M = T1 + xi u_s + z e_z`` and O2M is O1M shifted by the centre distance (Eq. 9)."""
    t1s, t1t = geo[5], geo[6]
    us, ut = geo[7], geo[8]
    ns_u, nz = geo[9], geo[10]
    a = geo[11]
    zg1, zg2 = geo[12], geo[13]
    nx, ny = ns_u * us, ns_u * ut
    # O1M x n = a1 x n + xi (u_s x n) + z (e_z x n) with a1 = (t1s, t1t, -zg1), and O2M x n
    # the same with a2 = (t1s - a, t1t, -zg2)
    a1 = (t1s, t1t, -zg1)
    a2 = (t1s - a, t1t, -zg2)
    for r in range(12):
        for c in range(3):
            p[r, c] = 0.0
    for c, nc in enumerate((nx, ny, nz)):
        p[c, 0] = nc
        p[6 + c, 0] = -nc
    p[3, 0] = a1[1] * nz - a1[2] * ny
    p[4, 0] = a1[2] * nx - a1[0] * nz
    p[5, 0] = a1[0] * ny - a1[1] * nx
    p[9, 0] = -(a2[1] * nz - a2[2] * ny)
    p[10, 0] = -(a2[2] * nx - a2[0] * nz)
    p[11, 0] = -(a2[0] * ny - a2[1] * nx)
    ux = (ut * nz, -us * nz, us * ny - ut * nx)  # u_s x n
    zx = (-ny, nx, 0.0)  # e_z x n
    for c in range(3):
        p[3 + c, 1] = ux[c]
        p[9 + c, 1] = -ux[c]
        p[3 + c, 2] = zx[c]
        p[9 + c, 2] = -zx[c]


@njit(cache=True, inline="always")
def _slice_stiffness(xi, xi_tab, k_tab, dl):
    """Stiffness of a slice [N/m]: the table's stiffness per unit contact length at ``xi``
    (linear interpolation) times the slice width ``dl``."""
    n_tab = xi_tab.size
    pos = (xi - xi_tab[0]) / (xi_tab[n_tab - 1] - xi_tab[0]) * (n_tab - 1)
    i0 = int(pos)
    if i0 >= n_tab - 1:
        i0 = n_tab - 2
    if i0 < 0:
        i0 = 0
    f = pos - i0
    return ((1.0 - f) * k_tab[i0] + f * k_tab[i0 + 1]) * dl


#: columns of a row of the slice cache (:meth:`MeshElement.kernel_arrays`): the slice
#: stiffness k dl [N/m], the deviation e [m], the abscissa xi [m], whether the slice is on the
#: path of contact, whether it is in the set of the cached tangent
_KDL, _E, _XI, _INSIDE, _IN_TANGENT = 0, 1, 2, 3, 4
#: the cache's last row: the pinion angle its rows belong to [rad], whether the tangent is kept
_ANGLE, _HAS_TANGENT = 0, 1
#: columns of the slice cache
CACHE_COLUMNS = 5


@njit(cache=True)
def _slice_geometry(angle, geo, xi_tab, k_tab, zs, dl, n_lines, dev, pitch1, pitch2, cache):
    """What a slice contributes at pinion ``angle`` [rad] whatever the DOFs: its abscissa,
    whether it is on the path of contact and there its k dl and deviation e, into the rows of
    ``cache`` (module docstring, Eq. 9); the last row records the angle, no tangent yet."""
    xi_a, xi_e, pbt, tanb = geo[0], geo[1], geo[2], geo[3]
    rb1 = geo[4]
    ns = zs.size
    z1n, z2n = pitch1.size, pitch2.size
    ca1, ca2, l1, l2, pexp, crown, slope, width = (dev[0], dev[1], dev[2], dev[3], dev[4],
                                                   dev[5], dev[6], dev[7])
    for s in range(ns):
        z = zs[s]
        w = (rb1 * angle - z * tanb) / pbt
        fl = math.floor(w + _SNAP)  # a line within _SNAP pitch of xi_A has entered
        fr = max(w - fl, 0.0)
        for j in range(n_lines):
            m = j * ns + s  # (cache[m, c], not a row view: a view per slice costs its refcount)
            xi = xi_a + pbt * (fr + j)
            cache[m, _XI] = xi
            ins = (xi >= xi_a) and (xi < xi_e)
            cache[m, _INSIDE] = 1.0 if ins else 0.0
            if ins:
                cache[m, _KDL] = _slice_stiffness(xi, xi_tab, k_tab, dl)
                # deviations (open the gap when > 0)
                e = 0.0
                if ca1 > 0.0 and xi > xi_e - l1:
                    e += ca1 * ((xi - (xi_e - l1)) / l1) ** pexp
                if ca2 > 0.0 and xi < xi_a + l2:
                    e += ca2 * (((xi_a + l2) - xi) / l2) ** pexp
                zr = 2.0 * z / width
                e += crown * zr * zr + slope * z / width
                pair = j - int(fl)
                if z1n > 0:
                    e += pitch1[pair % z1n]
                if z2n > 0:
                    e += pitch2[pair % z2n]
                cache[m, _E] = e
    last = cache[n_lines * ns]
    last[_ANGLE] = angle
    last[_HAS_TANGENT] = 0.0


@njit(cache=True)
def _mesh_kernel(angle, q, p, geo, xi_tab, k_tab, zs, dl, n_lines, dev, pitch1, pitch2, cache,
                 tangent, force, stiff, active, inside, delta, load, xis, zout):
    """Slices of all contact lines at pinion angle ``angle`` (module docstring), ``q`` the 12
    gear-node DOFs in the structure's frame and ``p`` the structure matrix P in that frame
    (:meth:`MeshElement.kernel_arrays`).

    ``cache`` and ``tangent`` are the mesh's (:meth:`MeshElement.kernel_arrays`): what depends
    on the angle only (:func:`_slice_geometry`) is computed once per angle, and the tangent
    ``stiff``, which depends on the angle and the contact set only, is assembled once per set
    (in a second sweep over the slices in contact). Every value is the one a fresh evaluation
    computes, bit for bit: the cache saves work, never changes a result. A Newton pass and the
    iterations of a coupled step evaluate the mesh at one angle.
    """
    ns = zs.size
    n = n_lines * ns
    last = cache[n]
    if not last[_ANGLE] == angle:  # (a NaN angle is never cached)
        _slice_geometry(angle, geo, xi_tab, k_tab, zs, dl, n_lines, dev, pitch1, pitch2, cache)
    # V = P u (_structure_matrix): the approach V.q - e = (P^T q).u - e, and the force
    # -sum k dl delta V = -P sum (k dl delta) u, through three sums instead of twelve
    pq0, pq1, pq2 = 0.0, 0.0, 0.0
    for c in range(12):
        pq0 += p[c, 0] * q[c]
        pq1 += p[c, 1] * q[c]
        pq2 += p[c, 2] * q[c]
    f0, f1, f2 = 0.0, 0.0, 0.0
    total = 0.0
    length = 0.0
    same_set = last[_HAS_TANGENT] > 0.0
    for s in range(ns):
        z = zs[s]
        for j in range(n_lines):
            m = j * ns + s
            xi = cache[m, _XI]
            xis[m] = xi
            zout[m] = z
            ins = cache[m, _INSIDE] > 0.0
            inside[m] = ins
            active[m] = False
            load[m] = 0.0
            delta[m] = 0.0
            if ins:
                d = (pq0 + pq1 * xi + pq2 * z) - cache[m, _E]
                delta[m] = d
                if d > 0.0:
                    active[m] = True
                    fm = cache[m, _KDL] * d
                    load[m] = fm
                    total += fm
                    length += dl
                    f0 += fm
                    f1 += fm * xi
                    f2 += fm * z
            if active[m] != (cache[m, _IN_TANGENT] > 0.0):
                same_set = False
    for c in range(12):
        force[c] = 0.0 - (p[c, 0] * f0 + p[c, 1] * f1 + p[c, 2] * f2)
    if same_set:
        for i in range(12):
            for j in range(12):
                stiff[i, j] = tangent[i, j]
        return total, length
    # K_gear = sum k dl V V^T = P (sum k dl u u^T) P^T: six moments of the slices in
    # contact instead of a 12 x 12 product per slice (scalars: the kernel allocates nothing)
    m00, m01, m02, m11, m12, m22 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    for s in range(ns):
        z = zs[s]
        for j in range(n_lines):
            m = j * ns + s
            cache[m, _IN_TANGENT] = 1.0 if active[m] else 0.0
            if active[m]:
                kdl = cache[m, _KDL]
                xi = cache[m, _XI]
                m00 += kdl
                m01 += kdl * xi
                m02 += kdl * z
                m11 += kdl * xi * xi
                m12 += kdl * xi * z
                m22 += kdl * z * z
    for i in range(12):
        p0, p1, p2 = p[i, 0], p[i, 1], p[i, 2]
        # (P mom)[i, :], each summed over k in order from 0.0
        a0 = ((0.0 + p0 * m00) + p1 * m01) + p2 * m02
        a1 = ((0.0 + p0 * m01) + p1 * m11) + p2 * m12
        a2 = ((0.0 + p0 * m02) + p1 * m12) + p2 * m22
        for j in range(12):
            stiff[i, j] = a0 * p[j, 0] + a1 * p[j, 1] + a2 * p[j, 2]
    for i in range(12):
        for j in range(12):
            tangent[i, j] = stiff[i, j]
    last[_HAS_TANGENT] = 1.0
    return total, length


class MeshElement:
    """The distributed mesh element of a gear pair (module docstring).

    Parameters
    ----------
    pair : GearPair
    line_load : float
        Reference load per unit contact length for the contact compliance [N/m]
        (``pair.nominal_line_load(torque)``).
    n_slices : int
        Slices across the face width (per contact line).
    deviations : ToothDeviations, optional
    gear_node_z : (float, float)
        Axial positions of the pinion and gear nodes relative to the face-width centre [m],
        in the element's own frame.
    n_table : int
        Samples of the stiffness per unit length along the path of contact.
    frame : (12, 12) array, optional
        ``T``: the pair's own frame (pinion at the origin turning about +z, gear at (a, 0),
        the contact-line convention of the module docstring) from the structure's frame of the
        12 gear-node DOFs, ``q_own = T q`` (:func:`pair_frame`). The element takes and gives
        DOFs, forces and stiffnesses in the structure's frame: ``P`` becomes ``T^T P``. None:
        the two frames are one (the paper's pair).

    Examples
    --------
    >>> from gear_fmu.mesh.geometry import GearPair
    >>> pair = GearPair(teeth=(20, 40), module=3e-3, pressure_angle=math.radians(20.0),
    ...                 centre_distance=0.09, face_width=(0.03, 0.03))
    >>> mesh = MeshElement(pair, line_load=6.5e4)
    >>> q = np.zeros(12); q[5] = 1e-4  # pinion twisted ahead by 0.1 mrad
    >>> st = mesh.evaluate(0.0, q)
    >>> int(st.active.sum()), st.total_load > 0
    (40, True)
    """

    def __init__(self, pair: GearPair, line_load: float, n_slices: int = 20,
                 deviations: ToothDeviations | None = None, gear_node_z=(0.0, 0.0),
                 n_table: int = 129, frame=None):
        if int(n_slices) != n_slices or n_slices < 1:
            raise ValueError(f"n_slices = {n_slices!r}: need an integer >= 1")
        self.pair = pair
        self.deviations = ToothDeviations() if deviations is None else deviations
        self.n_slices = int(n_slices)
        self.xi_table, self.k_table = mesh_stiffness_table(pair, line_load, n_table)
        self.line_load = float(line_load)
        b = pair.contact_width
        dz = b / self.n_slices
        self.z_slices = -0.5 * b + (np.arange(self.n_slices) + 0.5) * dz
        cb = math.cos(pair.base_helix_angle)
        self.dl = dz / cb
        xi_a, xi_e = pair.path_of_contact
        pbt = pair.base_pitch
        tanb = math.tan(pair.base_helix_angle)
        self.n_lines = math.ceil((xi_e - xi_a) / pbt) + 1
        ap = pair.operating_pressure_angle
        rb1 = pair.base_radius[0]
        self._geo = np.array([
            xi_a, xi_e, pbt, tanb, rb1,
            rb1 * math.cos(ap), -rb1 * math.sin(ap),  # T1
            math.sin(ap), math.cos(ap),  # u
            cb, math.sin(pair.base_helix_angle),  # n = cb u + sb e_z
            pair.centre_distance, float(gear_node_z[0]), float(gear_node_z[1]),
        ])
        d = self.deviations
        self._dev = np.array([d.tip_relief[0], d.tip_relief[1], d.relief_length[0],
                              d.relief_length[1], d.relief_exponent, d.crowning, d.lead_slope,
                              b])
        self._pitch = tuple(np.ascontiguousarray(p, dtype=float) for p in d.pitch_errors)
        for p, z, name in zip(self._pitch, pair.teeth, ("pinion", "gear"), strict=True):
            if p.size not in (0, z):
                raise ValueError(f"{name} pitch errors: {p.size} values for {z} teeth")
        self._mounting = np.asarray(d.mounting, dtype=float)
        self._runout = d.runout != (0.0, 0.0)
        self._has_errors = bool(self._runout or self._mounting.any())
        n = self.n_lines * self.n_slices
        self._n = n
        # what the kernel computes once per pinion angle and once per contact set (_mesh_kernel)
        self._cache = np.zeros((n + 1, CACHE_COLUMNS))
        self._cache[n, _ANGLE] = math.nan
        self._tangent = np.zeros((12, 12))
        # P of V = P u in the structure's frame (constant: the kernel takes it as it is)
        own = np.empty((12, 3))
        _structure_matrix(self._geo, own)
        te = np.zeros(12)
        te[5], te[11] = pair.base_radius
        if frame is None:
            self._frame = None
            self._p, self._te = own, te
        else:
            t = np.asarray(frame, dtype=float)
            if t.shape != (12, 12) or not np.allclose(t @ t.T, np.eye(12), atol=1e-12):
                raise ValueError("frame: an orthogonal (12, 12) matrix, q_own = T q")
            self._frame = t
            self._p = np.ascontiguousarray(t.T @ own)
            self._te = t.T @ te

    @property
    def mesh_stiffness_per_width(self) -> float:
        """Mean stiffness per unit face width of one tooth pair over the path [N/m^2]."""
        return float(np.mean(self.k_table)) / math.cos(self.pair.base_helix_angle)

    @property
    def event_period(self) -> float:
        """Pinion angle of one mesh period, ``2 pi / z1`` [rad]."""
        return 2.0 * math.pi / self.pair.teeth[0]

    def event_angles(self, angle0: float, angle1: float) -> np.ndarray:
        """Pinion angles in ``(angle0, angle1]`` at which a slice enters or leaves the path of
        contact (rigid-body kinematics, module docstring), sorted, duplicates merged [rad].

        Slice s at ``z_s`` carries the lines ``xi_A + p_bt (frac(w) + j)``,
        ``w = (r_b1 Theta1 - z_s tan(beta_b)) / p_bt``: a line enters at xi_A when w is an
        integer and the last one leaves at xi_E when ``frac(w) = frac(eps_alpha)``,
        ``eps_alpha = (xi_E - xi_A) / p_bt``. Between two such angles the set of slices on the
        path is fixed and the mesh stiffness is continuous in the angle; across one it jumps.
        Angles within 1e-9 p_bt / r_b1 of each other are merged.

        Examples
        --------
        A spur pair has two events per mesh period (an entry and an exit):

        >>> from gear_fmu.mesh.geometry import GearPair
        >>> pair = GearPair(teeth=(20, 40), module=3e-3, pressure_angle=math.radians(20.0),
        ...                 centre_distance=0.09, face_width=(0.03, 0.03))
        >>> mesh = MeshElement(pair, line_load=6.5e4)
        >>> mesh.event_angles(0.0, mesh.event_period).size
        2
        """
        pair = self.pair
        xi_a, xi_e = pair.path_of_contact
        pbt = pair.base_pitch
        rb1 = pair.base_radius[0]
        tanb = math.tan(pair.base_helix_angle)
        eps = (xi_e - xi_a) / pbt
        phases = np.unique([0.0, eps - math.floor(eps)])
        # w(angle) of every slice, then every w in (w0, w1] with frac(w) in phases
        shift = np.unique(self.z_slices * tanb / pbt)
        w0 = rb1 * angle0 / pbt - shift
        w1 = rb1 * angle1 / pbt - shift
        out = []
        for c in phases:
            k0 = np.floor(w0 - c) + 1.0
            k1 = np.floor(w1 - c)
            for s in range(shift.size):
                ks = np.arange(k0[s], k1[s] + 1.0)
                out.append((ks + c + shift[s]) * pbt / rb1)
        if not out:
            return np.empty(0)
        angles = np.sort(np.concatenate(out))
        angles = angles[(angles > angle0) & (angles <= angle1)]
        if angles.size > 1:
            keep = np.concatenate([[True], np.diff(angles) > 1e-9 * pbt / rb1])
            angles = angles[keep]
        return angles

    def error_displacement(self, pinion_angle: float) -> np.ndarray:
        """q_err: mounting errors and runouts as rigid gear-node displacements (12,), in the
        structure's frame (``mounting``, ``runout_phase``: in the pair's own frame)."""
        q = self._mounting.copy()
        if self._runout:
            d = self.deviations
            th2 = pinion_angle * self.pair.teeth[0] / self.pair.teeth[1]
            q[0] += d.runout[0] * math.cos(pinion_angle + d.runout_phase[0])
            q[1] += d.runout[0] * math.sin(pinion_angle + d.runout_phase[0])
            q[6] += d.runout[1] * math.cos(-th2 + d.runout_phase[1])
            q[7] += d.runout[1] * math.sin(-th2 + d.runout_phase[1])
        return q if self._frame is None else self._frame.T @ q

    def transmission_error(self, q) -> float | np.ndarray:
        """``r_b1 theta1 + r_b2 theta2`` [m] of the gear-node DOFs ``q`` (..., 12) in the
        structure's frame, the rotations taken in the pair's own frame (the pinion turning
        about +z): :func:`transmission_error` there."""
        q = np.asarray(q, dtype=float)
        if self._frame is None:
            return transmission_error(self.pair.base_radius, q)
        out = q @ self._te
        return float(out) if q.ndim == 1 else out

    @property
    def has_errors(self) -> bool:
        """True when runout or mounting errors displace the gear nodes seen by the mesh
        (:meth:`error_displacement`)."""
        return self._has_errors

    def kernel_arrays(self) -> tuple:
        """The arguments of the mesh kernel after (angle, q), in its order: what a compiled
        caller (:mod:`gear_fmu.step.kernel`) passes on. The last two are the mesh's cache of
        what depends on the angle and the contact set only (``_mesh_kernel``), which the
        kernel updates; the others are constant."""
        return (self._p, self._geo, self.xi_table, self.k_table, self.z_slices, self.dl,
                self.n_lines, self._dev, self._pitch[0], self._pitch[1], self._cache,
                self._tangent)

    def evaluate(self, pinion_angle: float, q12) -> MeshState:
        """Mesh force, tangent and contact set at a pinion angle [rad] and gear-node DOFs (12,)."""
        q = np.asarray(q12, dtype=float)
        if q.shape != (12,):
            raise ValueError(f"q12 shape {q.shape}: expected (12,)")
        qe = q + self.error_displacement(pinion_angle) if self.has_errors else q
        n = self._n
        force = np.empty(12)
        stiff = np.empty((12, 12))
        active = np.empty(n, dtype=np.bool_)
        inside = np.empty(n, dtype=np.bool_)
        delta = np.empty(n)
        load = np.empty(n)
        xi = np.empty(n)
        z = np.empty(n)
        total, length = _mesh_kernel(float(pinion_angle), qe, *self.kernel_arrays(), force,
                                     stiff, active, inside, delta, load, xi, z)
        te = self.transmission_error(q)
        return MeshState(force, stiff, active, delta, load, inside, xi, z, total, te,
                         {"contact_length": length})
