"""Two-node Timoshenko shaft element and rigid disc (paper Sec. 2.1).

The shaft axis is z. Each node carries the six DOFs of :mod:`gear_fmu.dofs`,
``(u, v, w, phi, psi, theta)``: translations along (s, t, z) and small rotations about (s, t, z).

Sign coupling of the two bending planes (right-handed frame, small rotations)
------------------------------------------------------------------------------
A rigid rotation ``psi`` about t moves a point at height z by ``psi e_t x z e_z = psi z e_s``, so
in the (s, z) plane the Euler-Bernoulli slope is ``du/dz = +psi``. A rotation ``phi`` about s moves
it by ``phi e_s x z e_z = -phi z e_t``: in the (t, z) plane ``dv/dz = -phi``. Both planes use
the same planar element on (deflection, slope-like rotation) = ``(u, psi)`` and ``(v, -phi)``.

Planar element
--------------
Interdependent interpolation of Friedman & Kosmatka (1993), "An improved two-node Timoshenko beam
finite element", Computers & Structures 47(3) 473-481: cubic deflection and quadratic rotation
that solve the static homogeneous Timoshenko equations exactly, with the shear parameter
``Phi = 12 E I / (kappa G A L^2)``. Stiffness and consistent mass (translational + rotary inertia)
are integrated exactly by Gauss quadrature of these shape functions:

    K = int E I N_r'^T N_r' + kappa G A (N_w' - N_r)^T (N_w' - N_r) dz
    M = int rho A N_w^T N_w + rho I N_r^T N_r dz

(the closed form of K is Przemieniecki's; the test suite checks it). Axial and torsional parts are
linear rods with consistent mass.

Gyroscopic matrix (not in the paper, which neglects it)
-------------------------------------------------------
A section spinning at Omega about +z (signed) with small rotations (phi, psi) has the angular
momentum ``rho I (phi' e_s + psi' e_t) + rho J Omega e_z'`` per unit length, its axis tilted to
``e_z' = e_z + psi e_s - phi e_t``; its rate gives the moments ``rho J Omega psi'`` about s and
``-rho J Omega phi'`` about t. On the element, with the section rotations interpolated as in M
(``psi = N_r q_s`` in the (s, z) plane, ``phi = -N_r T q_t`` in the (t, z) plane,
``T = diag(1, -1, 1, -1)``):

    M Xdd + Omega G Xd + K X = F,   G = rho J int (N_phi^T N_psi - N_psi^T N_phi) dz

skew-symmetric (:func:`timoshenko_gyroscopic`; Nelson & McVaugh (1976), "The dynamics of
rotor-bearing systems using finite elements", J. Eng. Ind. 98(2), 593-600, for the
Euler-Bernoulli element); a rigid disc's is ``I_p`` on (phi, psi)
(:func:`disc_gyroscopic`). A forward whirl (the same sense as the spin) is stiffened by it,
a backward one softened.

Shear coefficient of the hollow circular section: Cowper (1966), "The shear coefficient in
Timoshenko's beam theory", J. Appl. Mech. 33, 335-340, Table 1:

    kappa = 6 (1 + nu) (1 + m^2)^2 / [(7 + 6 nu) (1 + m^2)^2 + (20 + 12 nu) m^2],  m = D_i / D_o.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gear_fmu.dofs import DOF_PER_NODE, PHI, PSI, THETA, U, V, W

__all__ = [
    "HollowSection",
    "cowper_shear_coefficient",
    "disc_gyroscopic",
    "disc_matrices",
    "gyroscopic_coupling",
    "planar_rotary",
    "planar_timoshenko",
    "timoshenko_element",
    "timoshenko_gyroscopic",
]


def cowper_shear_coefficient(nu: float, diameter_ratio: float) -> float:
    """Cowper's shear coefficient of a hollow circular section.

    Parameters
    ----------
    nu : float
        Poisson's ratio [-], in (-1, 0.5].
    diameter_ratio : float
        m = D_i / D_o [-], in [0, 1).

    Returns
    -------
    float
        kappa [-]; 6(1+nu)/(7+6nu) for the solid section (0.886 at nu = 0.3), tending to
        2(1+nu)/(4+3nu) for a thin tube.

    Examples
    --------
    >>> round(cowper_shear_coefficient(0.3, 0.0), 4)
    0.8864
    """
    if not -1.0 < nu <= 0.5:
        raise ValueError(f"Poisson's ratio nu = {nu!r} must lie in (-1, 0.5]")
    if not 0.0 <= diameter_ratio < 1.0:
        raise ValueError(f"diameter ratio D_i/D_o = {diameter_ratio!r} must lie in [0, 1)")
    m2 = diameter_ratio**2
    a = (1.0 + m2) ** 2
    return 6.0 * (1.0 + nu) * a / ((7.0 + 6.0 * nu) * a + (20.0 + 12.0 * nu) * m2)


@dataclass(frozen=True)
class HollowSection:
    """Hollow circular shaft section and material (paper Table 2), SI units.

    Parameters
    ----------
    outer_diameter, inner_diameter : float
        D_o > D_i >= 0 [m].
    young : float
        Young's modulus E [Pa].
    poisson : float
        Poisson's ratio nu [-].
    density : float
        rho [kg/m^3].
    """

    outer_diameter: float
    inner_diameter: float
    young: float = 210e9
    poisson: float = 0.3
    density: float = 7800.0

    def __post_init__(self) -> None:
        for name in ("outer_diameter", "young", "density"):
            val = getattr(self, name)
            if not (math.isfinite(val) and val > 0.0):
                raise ValueError(f"{name} = {val!r} must be finite and > 0")
        if not (0.0 <= self.inner_diameter < self.outer_diameter):
            raise ValueError(
                f"inner_diameter = {self.inner_diameter!r} m must lie in "
                f"[0, outer_diameter = {self.outer_diameter!r} m)"
            )
        cowper_shear_coefficient(self.poisson, self.inner_diameter / self.outer_diameter)

    @property
    def area(self) -> float:
        """Cross-section area A [m^2]."""
        return math.pi / 4.0 * (self.outer_diameter**2 - self.inner_diameter**2)

    @property
    def second_moment(self) -> float:
        """Diametral second moment of area I [m^4]."""
        return math.pi / 64.0 * (self.outer_diameter**4 - self.inner_diameter**4)

    @property
    def polar_moment(self) -> float:
        """Polar second moment J = 2 I [m^4] (torsion constant of a circular tube)."""
        return 2.0 * self.second_moment

    @property
    def shear_modulus(self) -> float:
        """G = E / (2 (1 + nu)) [Pa]."""
        return self.young / (2.0 * (1.0 + self.poisson))

    @property
    def shear_coefficient(self) -> float:
        """Cowper's kappa [-]."""
        return cowper_shear_coefficient(self.poisson, self.inner_diameter / self.outer_diameter)

    @property
    def mass_per_length(self) -> float:
        """rho A [kg/m]."""
        return self.density * self.area


_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(5)  # exact to degree 9 on [-1, 1]


def _shape_functions(xi: float, length: float, phi_s: float):
    """Friedman-Kosmatka interdependent shape functions and their z-derivatives at xi = z/L."""
    c = 1.0 / (1.0 + phi_s)
    L = length
    nw = c * np.array([
        2 * xi**3 - 3 * xi**2 - phi_s * xi + 1 + phi_s,
        L * (xi**3 - (2 + phi_s / 2) * xi**2 + (1 + phi_s / 2) * xi),
        -(2 * xi**3 - 3 * xi**2 - phi_s * xi),
        L * (xi**3 - (1 - phi_s / 2) * xi**2 - (phi_s / 2) * xi),
    ])
    dnw = c / L * np.array([
        6 * xi**2 - 6 * xi - phi_s,
        L * (3 * xi**2 - (4 + phi_s) * xi + (1 + phi_s / 2)),
        -(6 * xi**2 - 6 * xi - phi_s),
        L * (3 * xi**2 - (2 - phi_s) * xi - phi_s / 2),
    ])
    nr = c * np.array([
        6.0 / L * (xi**2 - xi),
        3 * xi**2 - (4 + phi_s) * xi + 1 + phi_s,
        -6.0 / L * (xi**2 - xi),
        3 * xi**2 - (2 - phi_s) * xi,
    ])
    dnr = c / L * np.array([
        6.0 / L * (2 * xi - 1),
        6 * xi - (4 + phi_s),
        -6.0 / L * (2 * xi - 1),
        6 * xi - (2 - phi_s),
    ])
    return nw, dnw, nr, dnr


def planar_timoshenko(
    length: float, ei: float, kga: float, rho_a: float, rho_i: float
) -> tuple[np.ndarray, np.ndarray]:
    """Planar Timoshenko element on (w1, r1, w2, r2) with r the section rotation, dw/dz ~ r.

    Parameters
    ----------
    length : float
        Element length L [m].
    ei : float
        Bending stiffness E I [N m^2].
    kga : float
        Shear stiffness kappa G A [N]; ``math.inf`` gives the Euler-Bernoulli element.
    rho_a, rho_i : float
        Mass per length rho A [kg/m] and rotary inertia per length rho I [kg m].

    Returns
    -------
    (K, M) : tuple of (4, 4) arrays
        Stiffness [N/m, N, N m] and consistent mass [kg, kg m, kg m^2].
    """
    phi_s = _shear_parameter(length, ei, kga)
    k = np.zeros((4, 4))
    m = np.zeros((4, 4))
    for xg, wg in zip(_GAUSS_X, _GAUSS_W, strict=True):
        xi = 0.5 * (xg + 1.0)
        wt = 0.5 * wg * length
        nw, dnw, nr, dnr = _shape_functions(xi, length, phi_s)
        k += wt * ei * np.outer(dnr, dnr)
        if not math.isinf(kga):
            gam = dnw - nr
            k += wt * kga * np.outer(gam, gam)
        m += wt * (rho_a * np.outer(nw, nw) + rho_i * np.outer(nr, nr))
    return k, m


def _rigidities(section: HollowSection) -> tuple[float, float]:
    """``(E I [N m^2], kappa G A [N])`` of a section: the bending and shear stiffnesses of the
    planar element."""
    s = section
    return s.young * s.second_moment, s.shear_coefficient * s.shear_modulus * s.area


def _shear_parameter(length: float, ei: float, kga: float) -> float:
    """Phi = 12 E I / (kappa G A L^2) [-] (0 for the Euler-Bernoulli element, kga = inf)."""
    if not (length > 0.0 and math.isfinite(length)):
        raise ValueError(f"element length = {length!r} m must be finite and > 0")
    return 0.0 if math.isinf(kga) else 12.0 * ei / (kga * length**2)


def planar_rotary(length: float, ei: float, kga: float) -> np.ndarray:
    """``int N_r^T N_r dz`` (4, 4) [m, m^2, m^3] of the planar element on (w1, r1, w2, r2): the
    section rotation's consistent matrix (times rho I the rotary inertia of M, times rho J
    Omega the gyroscopic coupling of the two planes; module docstring).

    Parameters
    ----------
    length, ei, kga : float
        As :func:`planar_timoshenko`.
    """
    phi_s = _shear_parameter(length, ei, kga)
    r = np.zeros((4, 4))
    for xg, wg in zip(_GAUSS_X, _GAUSS_W, strict=True):
        _, _, nr, _ = _shape_functions(0.5 * (xg + 1.0), length, phi_s)
        r += 0.5 * wg * length * np.outer(nr, nr)
    return r


def gyroscopic_coupling(rotary: np.ndarray, polar: float, nodes: int) -> np.ndarray:
    """The skew gyroscopic matrix (6 nodes, 6 nodes) per unit spin from the rotations' matrix
    ``rotary`` on (w1, r1, ...) of each plane and the polar inertia factor ``polar``
    (module docstring): rows phi of the (t, z) plane against psi of the (s, z) plane."""
    n = DOF_PER_NODE
    s_idx = [i for node in range(nodes) for i in (n * node + U, n * node + PSI)]
    t_idx = [i for node in range(nodes) for i in (n * node + V, n * node + PHI)]
    t = np.diag([1.0, -1.0] * nodes)
    g = np.zeros((n * nodes, n * nodes))
    g[np.ix_(t_idx, s_idx)] = -polar * (t @ rotary)
    g[np.ix_(s_idx, t_idx)] = polar * (rotary @ t)
    return g


def timoshenko_gyroscopic(section: HollowSection, length: float) -> np.ndarray:
    """Gyroscopic matrix G (12, 12) per unit spin [kg m^2 ... ] of a 2-node shaft element:
    ``Omega G Xd`` joins ``C Xd`` in Eq. (9) for a shaft spinning at Omega [rad/s] about +z
    (module docstring). Skew-symmetric; DOF order as :func:`timoshenko_element`.

    Parameters
    ----------
    section : HollowSection
    length : float
        Element length [m].
    """
    return gyroscopic_coupling(planar_rotary(length, *_rigidities(section)),
                               section.density * section.polar_moment, 2)


def disc_gyroscopic(polar_inertia: float) -> np.ndarray:
    """Gyroscopic matrix (6, 6) per unit spin of a rigid disc on one node: ``G[phi, psi] =
    I_p``, ``G[psi, phi] = -I_p`` (module docstring) [kg m^2].

    Examples
    --------
    >>> g = disc_gyroscopic(2.0)
    >>> float(g[3, 4]), float(g[4, 3])
    (2.0, -2.0)
    """
    if not (math.isfinite(polar_inertia) and polar_inertia >= 0.0):
        raise ValueError(f"disc polar_inertia = {polar_inertia!r} kg m^2 must be finite and >= 0")
    return gyroscopic_coupling(np.diag([0.0, 1.0]), polar_inertia, 1)


def timoshenko_element(section: HollowSection, length: float) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and consistent mass (12, 12) of a 2-node shaft element along z (the shaft part
    of M and K in Eq. 9).

    DOF order: node 1 then node 2, each ``(u, v, w, phi, psi, theta)`` (:mod:`gear_fmu.dofs`).
    Bending in (s, z) on ``(u, psi)``, in (t, z) on ``(v, -phi)`` (module docstring), axial rod on
    ``w``, torsion rod on ``theta`` (G J, rho J). Paper Sec. 2.1.

    Parameters
    ----------
    section : HollowSection
        Section and material.
    length : float
        Element length [m].

    Returns
    -------
    (K, M) : tuple of (12, 12) arrays, SI.
    """
    s = section
    kp, mp = planar_timoshenko(length, *_rigidities(s), s.density * s.area,
                               s.density * s.second_moment)
    k = np.zeros((12, 12))
    m = np.zeros((12, 12))
    n = DOF_PER_NODE
    # (s, z) plane: (u1, psi1, u2, psi2)
    idx = [U, PSI, n + U, n + PSI]
    k[np.ix_(idx, idx)] += kp
    m[np.ix_(idx, idx)] += mp
    # (t, z) plane: (v1, -phi1, v2, -phi2)
    idx = [V, PHI, n + V, n + PHI]
    t = np.diag([1.0, -1.0, 1.0, -1.0])
    k[np.ix_(idx, idx)] += t @ kp @ t
    m[np.ix_(idx, idx)] += t @ mp @ t
    rod_k = np.array([[1.0, -1.0], [-1.0, 1.0]]) / length
    rod_m = np.array([[2.0, 1.0], [1.0, 2.0]]) * length / 6.0
    idx = [W, n + W]
    k[np.ix_(idx, idx)] += s.young * s.area * rod_k
    m[np.ix_(idx, idx)] += s.density * s.area * rod_m
    idx = [THETA, n + THETA]
    k[np.ix_(idx, idx)] += s.shear_modulus * s.polar_moment * rod_k
    m[np.ix_(idx, idx)] += s.density * s.polar_moment * rod_m
    return k, m


def disc_matrices(mass: float, diametral_inertia: float, polar_inertia: float) -> np.ndarray:
    """Mass matrix (6, 6) of a rigid disc on one node: diag(m, m, m, I_d, I_d, I_p).

    Parameters
    ----------
    mass : float
        Disc mass [kg].
    diametral_inertia : float
        Moment of inertia about a diameter through the centre of mass [kg m^2].
    polar_inertia : float
        Moment of inertia about the shaft axis [kg m^2].
    """
    for name, val in (("mass", mass), ("diametral_inertia", diametral_inertia),
                      ("polar_inertia", polar_inertia)):
        if not (math.isfinite(val) and val >= 0.0):
            raise ValueError(f"disc {name} = {val!r} must be finite and >= 0")
    return np.diag([mass, mass, mass, diametral_inertia, diametral_inertia, polar_inertia])
