"""The stability threshold (gear_fmu.modal.whirl) of a symmetric rigid rotor in two identical
short plain bearings, against the closed form.

Closed form, written apart from the code: the short-bearing (Ocvirk) coefficients in the
frame of the load, ``K = (W/c) a(eps)``, ``C = (W/(c Omega)) b(eps)`` (Friswell et al. (2010),
"Dynamics of Rotating Machines", Sec. 5.5), the eccentricity from the load
``W = 6 mu Omega R^2 (R/c)^2 (2 lambda^3/3) eps sqrt(pi^2 (1 - eps^2) + 16 eps^2) /
(2 (1 - eps^2)^2)``, and Lund's threshold of a rigid rotor of mass m per bearing: the
cylindrical whirl ``x = X exp(i nu t)`` is neutral when ``m nu^2 = K_eq``,

    K_eq = (Kxx Cyy + Kyy Cxx - Kxy Cyx - Kyx Cxy) / (Cxx + Cyy),
    nu^2 = ((Kxx - K_eq)(Kyy - K_eq) - Kxy Kyx) / (Cxx Cyy - Cxy Cyx).

The code's path: the short-bearing model's static equilibrium and 8 coefficients at each speed
(:mod:`bearing_fmu.short_bearing`, :func:`bearing_fmu.static.static_equilibrium`), the damped
modes (:func:`gear_fmu.modal.damped_modes.damped_eigen`) and the threshold from their damping
ratios (:func:`gear_fmu.modal.whirl.stability_threshold`).
"""

import math

import numpy as np
import scipy.optimize

from bearing_fmu.base import BearingData
from bearing_fmu.short_bearing import ShortBearing
from bearing_fmu.static import static_equilibrium
from gear_fmu.modal.damped_modes import damped_eigen
from gear_fmu.modal.whirl import stability_threshold

BEARING = BearingData(diameter=0.05, length=0.02, clearance=50e-6, viscosity=0.02)
MASS = 20.0  # kg per bearing
LOAD = MASS * 9.81  # N per bearing: the rotor's weight


def short_coefficients(e):
    """Dimensionless (a, b) of the short bearing at eccentricity ratio e (module docstring)."""
    h0 = 1.0 / (math.pi**2 * (1 - e**2) + 16 * e**2) ** 1.5
    s = math.sqrt(1 - e**2)
    p2 = math.pi**2
    a = h0 * np.array([
        [4 * (p2 * (2 - e**2) + 16 * e**2), math.pi * (p2 * (1 - e**2) ** 2 - 16 * e**4) / (e * s)],
        [-math.pi * (p2 * (1 - e**2) * (1 + 2 * e**2) + 32 * e**2 * (1 + e**2)) / (e * s),
         4 * (p2 * (1 + 2 * e**2) + 32 * e**2 * (1 + e**2) / (1 - e**2))]])
    cross = -8 * (p2 * (1 + 2 * e**2) - 16 * e**2)
    b = h0 * np.array([
        [2 * math.pi * s * (p2 * (1 + 2 * e**2) - 16 * e**2) / e, cross],
        [cross, 2 * math.pi * (p2 * (1 - e**2) ** 2 + 48 * e**2) / (e * s)]])
    return a, b


def eccentricity(omega):
    lam, scale = BEARING.lambda_, BEARING.force_scale(omega)

    def excess(e):
        return (scale * 2 * lam**3 / 3 * e * math.sqrt(math.pi**2 * (1 - e**2) + 16 * e**2)
                / (2 * (1 - e**2) ** 2) - LOAD)

    return scipy.optimize.brentq(excess, 1e-9, 1 - 1e-12, xtol=1e-15)


def closed_form_threshold():
    def margin(omega):
        a, b = short_coefficients(eccentricity(omega))
        k_eq = ((a[0, 0] * b[1, 1] + a[1, 1] * b[0, 0] - a[0, 1] * b[1, 0] - a[1, 0] * b[0, 1])
                / (b[0, 0] + b[1, 1]))
        whirl2 = (((a[0, 0] - k_eq) * (a[1, 1] - k_eq) - a[0, 1] * a[1, 0])
                  / (b[0, 0] * b[1, 1] - b[0, 1] * b[1, 0]))  # (nu / Omega)^2
        # m nu^2 - K_eq with K = (W/c) a and nu^2 = Omega^2 whirl2: m = W/g
        return omega**2 * whirl2 * BEARING.clearance / 9.81 - k_eq

    return scipy.optimize.brentq(margin, 100.0, 5000.0, xtol=1e-9)


def damping_ratios(speeds) -> list:
    """The damping ratios of the rotor's oscillating modes at each speed [rad/s], by the code's
    path (module docstring): the short-bearing model's static equilibrium and 8 coefficients,
    the damped modes of the cylindrical whirl (mass per bearing)."""
    model = ShortBearing(BEARING)
    out = []
    for omega in speeds:
        st = static_equilibrium(model, (0.0, -LOAD), omega)
        modes = damped_eigen(MASS * np.eye(2), st.result.damping, st.result.stiffness)
        out.append(modes.damping_ratio[~modes.overdamped])
    return out


def test_the_closed_form_coefficients_are_the_models():
    """Frame-free checks that the two derivations describe one bearing: trace and determinant
    of K and C, and the load, to round-off."""
    model = ShortBearing(BEARING)
    for omega in (200.0, 1200.0, 3000.0):
        st = static_equilibrium(model, (0.0, -LOAD), omega)
        assert math.isclose(st.eccentricity, eccentricity(omega), rel_tol=1e-9)
        a, b = short_coefficients(st.eccentricity)
        k = LOAD / BEARING.clearance * a
        c = LOAD / (BEARING.clearance * omega) * b
        km, cm = st.result.stiffness, st.result.damping
        for f in (np.trace, np.linalg.det):
            assert math.isclose(f(k), f(km), rel_tol=1e-9)
            assert math.isclose(f(c), f(cm), rel_tol=1e-9)


def test_rigid_rotor_threshold_within_two_per_mille_of_lunds():
    """On speeds 50 rad/s apart (the threshold between two of them), linear interpolation of
    the least damping ratio: measured 1.6e-4 from the closed form (1209.16 against 1208.96
    rad/s); bound 2e-3, 12x, well inside the 2 % asked."""
    expected = closed_form_threshold()
    speeds = np.arange(600.0, 1850.0, 50.0)
    zetas = damping_ratios(speeds)
    found = stability_threshold(speeds, zetas)
    assert speeds[0] < expected < speeds[-1]
    assert math.isclose(found, expected, rel_tol=2e-3), (found, expected)
    # below it every mode is damped, above it one is not
    assert min(zetas[0]) > 0.0 and min(zetas[-1]) < 0.0
