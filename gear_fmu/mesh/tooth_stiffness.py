"""Mesh stiffness per unit contact length from Weber & Banaschek (paper Sec. 2.1).

The compliance of one pair of teeth in contact at abscissa ``xi`` of the line of action is the
sum, in series, of (per unit face width, plane strain; F the normal load per unit width):

1. Tooth bending, shear and compression of each tooth (Weber 1949, energy method; the form with
   the load line's intersection with the tooth centre line is Cornell's, 1981). The tooth is a
   cantilever of half thickness ``x(y)`` on its centre line, clamped at the root circle
   (``y = 0``), loaded at the contact point P (height ``y_P``) along the involute normal, at the
   load angle ``alpha_F = alpha_M - psi_M`` from the perpendicular to the centre line
   (``alpha_M`` the pressure angle at P, ``psi_M`` its half angular thickness). The load line
   cuts the centre line at ``y_C``. Castigliano's theorem gives the approach along the load::

       delta_B = F cos^2(alpha_F) int_0^y_P 12 (y_C - y)^2 / (E' (2x)^3) dy
       delta_S = F cos^2(alpha_F) int_0^y_P 1.2 / (G 2x) dy
       delta_N = F sin^2(alpha_F) int_0^y_P 1 / (E' 2x) dy

   with ``E' = E / (1 - nu^2)`` (wide teeth) and ``G = E / (2 (1 + nu))``. Above the base circle
   the profile is the involute; below it (pinion of Table 1) the flank is continued parallel to
   the centre line down to the root circle (a choice: between the radial line of the
   potential-energy literature, which thins the root, and the generated trochoid, which thickens
   it).

2. Foundation (gear body) of each tooth: Weber & Banaschek (1953) in the form given by Cornell
   (1981) and Sainsot et al. (2004)::

       delta_F = F cos^2(alpha_F) / E
                 * [L* (u_F / S_F)^2 + M* (u_F / S_F) + P* (1 + Q* tan^2 alpha_F)]
       L* = 16.67 (1 - nu^2) / pi,  M* = 2 (1 - nu - 2 nu^2),
       P* = 1.534,  Q* = 1 / (2.4 (1 + nu))

   ``u_F = y_C`` (load line on the centre line, from the root circle), ``S_F = 2 x(0)`` (tooth
   thickness at the root circle).

3. Contact of the two flanks (Weber's plane-strain Hertz approach between the two tooth centre
   lines)::

       delta_H = 2 F (1 - nu^2) / (pi E) [ln(2 h1 / a_H) + ln(2 h2 / a_H) - nu / (1 - nu)]
       a_H = sqrt(8 F rho (1 - nu^2) / (pi E)),   1/rho = 1/rho1 + 1/rho2

   with ``h_i`` the distance from P to the centre line of tooth i along the load line and
   ``rho_i`` the involute radii of curvature (``xi`` and ``|T1T2| - xi``). delta_H grows like
   ``F ln(1/F)``; it is linearised as a secant at a reference line load (the mean static load),
   so that the elemental stiffness is a function of position only (paper: "initialised").

The stiffness per unit face width is ``k(xi) = 1 / (c_1 + c_2 + c_H)``, the c's the compliances
above per unit load; the mean over the path of contact is checked against ISO 6336-1 method B in
the tests. For helical pairs the transverse section is used and the stiffness per unit length of
contact line is ``k cos(beta_b)`` (a slice of width dz carries a contact line of length
``dz / cos(beta_b)``), so a given transverse section has the stiffness of the spur pair.

References: C. Weber, "The deformation of loaded gears and the effect on their load carrying
capacity", DSIR Sponsored Research (Germany) Report 3, 1949; C. Weber, K. Banaschek,
"Formänderung und Profilrücknahme bei gerad- und schrägverzahnten Rädern", Schriftenreihe
Antriebstechnik 11, Vieweg, 1953; R.W. Cornell, J. Mech. Des. 103 (1981) 447-459; P. Sainsot,
P. Velex, O. Duverger, J. Mech. Des. 126 (2004) 748-752.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from gear_fmu.mesh.geometry import GearPair

__all__ = ["ToothPairCompliance", "mesh_stiffness_table", "tooth_compliance"]

_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(24)


def _profile(pair: GearPair, gear: int, radius: float):
    """Involute point at ``radius``: (height above the root circle y [m], half thickness x [m])."""
    psi = pair.half_tooth_angle(gear, radius)
    return radius * math.cos(psi) - pair.root_radius[gear], radius * math.sin(psi)


def _beam_integrals(pair: GearPair, gear: int, r_p: float, y_c: float, n_panels: int = 8):
    """(int 12 (y_C - y)^2 / (2x)^3 dy, int 1 / (2x) dy) from the root circle to the contact
    point at radius r_p, per unit width [1/m, -]."""
    rb, rf = pair.base_radius[gear], pair.root_radius[gear]
    i_b = 0.0
    i_a = 0.0
    r_low = max(rb, rf)
    y_low, x_low = _profile(pair, gear, r_low)
    if rf < rb:
        # flank parallel to the centre line below the base circle (module docstring)
        y0, y1 = 0.0, y_low
        t = 2.0 * x_low
        i_b += 12.0 / t**3 * ((y_c - y0) ** 3 - (y_c - y1) ** 3) / 3.0
        i_a += (y1 - y0) / t
    # psi(r) = psi0 - inv(alpha_r) (GearPair.half_tooth_angle), psi0 its value at r_b
    psi0 = pair.half_tooth_angle(gear, rb)
    return _involute_integrals(np.linspace(r_low, r_p, n_panels + 1), rb, rf, psi0, y_c,
                               _GAUSS_X, _GAUSS_W, i_b, i_a, 2.0, 3.0)


@njit(cache=True)
def _involute_integrals(edges, rb, rf, psi0, y_c, gauss_x, gauss_w, i_b, i_a, two, three):
    """The involute part of :func:`_beam_integrals`: Gauss-Legendre in r on the panels
    between ``edges``, added to ``(i_b, i_a)``; dy/dr = cos psi + sin psi tan(alpha_r)
    (d psi / dr = -tan(alpha_r) / r). The powers are calls of ``pow`` with the exponents
    ``two`` = 2 and ``three`` = 3 passed at run time, as Python's ``**`` computes them (the
    compiler would turn a constant square into a product, which rounds differently)."""
    for p in range(edges.size - 1):
        r0 = edges[p]
        r1 = edges[p + 1]
        mid = 0.5 * (r0 + r1)
        half = 0.5 * (r1 - r0)
        for k in range(gauss_x.size):
            r = mid + half * gauss_x[k]
            w = half * gauss_w[k]
            alpha_r = math.acos(min(1.0, rb / r))
            psi = psi0 - (math.tan(alpha_r) - alpha_r)
            y = r * math.cos(psi) - rf
            x = r * math.sin(psi)
            dy_dr = math.cos(psi) + math.sin(psi) * math.sqrt(max(r * r - rb * rb, 0.0)) / rb
            t = 2.0 * x
            i_b += w * dy_dr * 12.0 * math.pow(y_c - y, two) / math.pow(t, three)
            i_a += w * dy_dr / t
    return i_b, i_a


def tooth_compliance(pair: GearPair, gear: int, radius: float):
    """Compliances of one tooth loaded at ``radius`` on its involute, per unit width.

    Returns
    -------
    (c_tooth, c_foundation, h) : float
        Bending + shear + compression and foundation compliances [m^2/N] (approach along the
        load line per unit load per unit width), and the distance h from the contact point to
        the tooth centre line along the load line [m] (for the contact term).
    """
    e, nu = pair.young, pair.poisson
    rb = pair.base_radius[gear]
    if not (rb <= radius <= pair.tip_radius[gear] * (1 + 1e-12)):
        raise ValueError(f"radius {radius!r} m outside the involute of wheel {gear} "
                         f"[{rb!r}, {pair.tip_radius[gear]!r}] m")
    alpha_m = math.acos(min(1.0, rb / radius))
    psi_m = pair.half_tooth_angle(gear, radius)
    alpha_f = alpha_m - psi_m
    y_p, x_p = _profile(pair, gear, radius)
    y_c = y_p - x_p * math.tan(alpha_f)
    i_b, i_a = _beam_integrals(pair, gear, radius, y_c)
    e_plane = e / (1.0 - nu * nu)
    g = e / (2.0 * (1.0 + nu))
    c2, s2 = math.cos(alpha_f) ** 2, math.sin(alpha_f) ** 2
    c_tooth = c2 * (i_b / e_plane + 1.2 * i_a / g) + s2 * i_a / e_plane
    _, x_root = _profile(pair, gear, max(rb, pair.root_radius[gear]))
    s_f = 2.0 * x_root
    ratio = y_c / s_f
    l_star = 16.67 * (1.0 - nu * nu) / math.pi
    m_star = 2.0 * (1.0 - nu - 2.0 * nu * nu)
    p_star, q_star = 1.534, 1.0 / (2.4 * (1.0 + nu))
    c_found = c2 / e * (l_star * ratio**2 + m_star * ratio
                        + p_star * (1.0 + q_star * math.tan(alpha_f) ** 2))
    h = x_p / math.cos(alpha_f)
    return c_tooth, c_found, h


class ToothPairCompliance:
    """Compliance of one pair of teeth in contact at abscissa xi (module docstring).

    Parameters
    ----------
    pair : GearPair
    line_load : float
        Reference load per unit contact length for the secant of the contact term [N/m]
        (:meth:`gear_fmu.mesh.geometry.GearPair.nominal_line_load`).
    """

    def __init__(self, pair: GearPair, line_load: float):
        if not (math.isfinite(line_load) and line_load > 0.0):
            raise ValueError(f"line_load = {line_load!r} N/m must be finite and > 0")
        self.pair = pair
        self.line_load = float(line_load)

    def components(self, xi: float) -> dict:
        """Compliances per unit face width [m^2/N] at abscissa xi [m] on T1T2."""
        pair = self.pair
        r1, r2 = pair.contact_radius(xi)
        t1, f1, h1 = tooth_compliance(pair, 0, r1)
        t2, f2, h2 = tooth_compliance(pair, 1, r2)
        e, nu = pair.young, pair.poisson
        rho1, rho2 = xi, pair.line_of_action_length - xi
        rho = rho1 * rho2 / (rho1 + rho2)
        w = self.line_load
        a_h = math.sqrt(8.0 * w * rho * (1.0 - nu * nu) / (math.pi * e))
        c_h = 2.0 * (1.0 - nu * nu) / (math.pi * e) * (
            math.log(2.0 * h1 / a_h) + math.log(2.0 * h2 / a_h) - nu / (1.0 - nu))
        return {"tooth_pinion": t1, "foundation_pinion": f1, "tooth_gear": t2,
                "foundation_gear": f2, "contact": c_h}

    def stiffness(self, xi: float) -> float:
        """Stiffness per unit face width of the tooth pair at xi [N/m^2]."""
        return 1.0 / sum(self.components(xi).values())


def mesh_stiffness_table(pair: GearPair, line_load: float, n: int = 129):
    """Stiffness per unit length of contact line sampled over the path of contact.

    Returns
    -------
    xi : (n,) abscissae from xi_A to xi_E [m]
    k : (n,) stiffness per unit contact length ``k(xi) cos(beta_b)`` [N/m^2]
    """
    if int(n) != n or n < 2:
        raise ValueError(f"n = {n!r}: need an integer >= 2")
    xi_a, xi_e = pair.path_of_contact
    xi = np.linspace(xi_a, xi_e, int(n))
    model = ToothPairCompliance(pair, line_load)
    k = np.array([model.stiffness(v) for v in xi]) * math.cos(pair.base_helix_angle)
    return xi, k
