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
linear rods with consistent mass. Gyroscopic terms are neglected, as in the paper.

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
    "disc_matrices",
    "planar_timoshenko",
    "timoshenko_element",
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
    if not (length > 0.0 and math.isfinite(length)):
        raise ValueError(f"element length = {length!r} m must be finite and > 0")
    phi_s = 0.0 if math.isinf(kga) else 12.0 * ei / (kga * length**2)
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
    ei = s.young * s.second_moment
    kga = s.shear_coefficient * s.shear_modulus * s.area
    kp, mp = planar_timoshenko(length, ei, kga, s.density * s.area, s.density * s.second_moment)
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
