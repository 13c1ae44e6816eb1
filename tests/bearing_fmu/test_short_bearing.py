"""Short-bearing theory against independent closed forms and quadrature."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from bearing_fmu import BearingData, BearingError, EccentricityError
from bearing_fmu.short_bearing import ShortBearing, ocvirk_static_force
from tests.helpers import numeric_jacobian

BEARING = BearingData(diameter=0.070, length=0.050, clearance=150e-6, viscosity=0.0288)
STATES = [
    (0.5, 0.0, 0.0, 0.0),
    (0.3, -0.4, 0.1, -0.05),
    (-0.6, 0.5, 0.02, 0.3),
    (0.1, 0.05, -0.2, 0.1),
    (0.9, 0.2, 0.0, 0.0),
    (0.0, 0.0, 0.05, 0.0),
]


def quad_force(lam, x, y, xd, yd):
    """Eq. (5) with p = f+ (lam^2 - xi^2) / (2 h^3), integrated adaptively (independent)."""

    def f(t):
        return max(0.0, (y + 2 * xd) * math.cos(t) + (2 * yd - x) * math.sin(t))

    def h(t):
        return 1 - x * math.cos(t) - y * math.sin(t)

    k = -2 * lam**3 / 3
    kw = dict(limit=400, epsabs=1e-13, epsrel=1e-12)
    return np.array([
        k * quad(lambda t: f(t) * math.cos(t) / h(t) ** 3, 0, 2 * math.pi, **kw)[0],
        k * quad(lambda t: f(t) * math.sin(t) / h(t) ** 3, 0, 2 * math.pi, **kw)[0],
    ])


@pytest.mark.parametrize("eps", [0.05, 0.3, 0.6, 0.9, 0.98])
def test_static_force_equals_ocvirk_closed_form(eps):
    ff = ShortBearing(BEARING).dimensionless(eps, 0.0)
    np.testing.assert_allclose(ff.force, ocvirk_static_force(BEARING.lambda_, eps), rtol=1e-12)


@pytest.mark.parametrize("state", STATES)
def test_dynamic_force_equals_adaptive_quadrature(state):
    ff = ShortBearing(BEARING).dimensionless(*state)
    ref = quad_force(BEARING.lambda_, *state)
    assert np.abs(ff.force - ref).max() <= 1e-10 * np.abs(ref).max()


@pytest.mark.parametrize("state", STATES)
def test_jacobians_match_central_differences(state):
    model = ShortBearing(BEARING)
    ff = model.dimensionless(*state)
    analytic = np.hstack([ff.d_position, ff.d_velocity])
    numeric = numeric_jacobian(model, state)
    assert np.abs(analytic - numeric).max() <= 1e-4 * np.abs(analytic).max()


def test_damping_matrix_symmetric():
    ff = ShortBearing(BEARING).dimensionless(0.4, -0.3, 0.05, 0.02)
    assert ff.d_velocity[0, 1] == pytest.approx(ff.d_velocity[1, 0], rel=1e-12)


def test_isotropy_rotation_of_state_rotates_force():
    model = ShortBearing(BEARING)
    x, y, xd, yd = 0.5, 0.1, 0.03, -0.02
    base = model.dimensionless(x, y, xd, yd).force
    for ang in (0.3, 1.7, -2.5):
        c, s = math.cos(ang), math.sin(ang)
        rot = np.array([[c, -s], [s, c]])
        px, py = rot @ [x, y]
        vx, vy = rot @ [xd, yd]
        np.testing.assert_allclose(model.dimensionless(px, py, vx, vy).force, rot @ base,
                                   rtol=1e-12, atol=1e-14)


def test_si_scaling():
    model = ShortBearing(BEARING)
    omega, c = 325.0, BEARING.clearance
    x, y, xd, yd = 60e-6, -50e-6, 1e-3, 2e-3
    r = model.evaluate(x, y, xd, yd, omega)
    ff = model.dimensionless(x / c, y / c, xd / (c * omega), yd / (c * omega))
    fs = 6 * BEARING.viscosity * omega * BEARING.radius**2 * (BEARING.radius / c) ** 2
    np.testing.assert_allclose(r.force, fs * ff.force, rtol=1e-14)
    np.testing.assert_allclose(r.stiffness, -fs / c * ff.d_position, rtol=1e-14)
    np.testing.assert_allclose(r.damping, -fs / (c * omega) * ff.d_velocity, rtol=1e-14)


def test_bad_input_is_named():
    model = ShortBearing(BEARING)
    with pytest.raises(EccentricityError, match=r"1\.2.*< 1"):
        model.dimensionless(1.2, 0.0)
    with pytest.raises(EccentricityError):
        model.evaluate(150e-6, 0.0, 0.0, 0.0, 325.0)
    with pytest.raises(BearingError, match="nan"):
        model.dimensionless(float("nan"), 0.0)
    with pytest.raises(BearingError, match="omega"):
        model.evaluate(0.0, 0.0, 0.0, 0.0, -1.0)
    with pytest.raises(BearingError, match="clearance"):
        BearingData(0.07, 0.05, -1e-4, 0.0288)
    with pytest.raises(BearingError, match="viscosity"):
        BearingData(0.07, 0.05, 1e-4, 0.0)
