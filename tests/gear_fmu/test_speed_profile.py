"""A run-up's kinematics and unbalance (docs/equations.md "Run-ups") against independent
computations: the angle against a quadrature of the speed, the acceleration against a finite
difference of it, the unbalance force against the reaction of its mass, whose acceleration is
taken by finite differences of its position."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from gear_fmu.loads import accelerated_unbalance_coefficients, unbalance_force
from gear_fmu.speed_profile import SpeedProfile
from gear_fmu.system import Unbalances

UP = SpeedProfile.ramp(100.0, 400.0, t_start=0.2, duration=0.5)
DOWN = SpeedProfile.ramp(400.0, 150.0, t_start=0.0, duration=0.25)
TABLE = SpeedProfile((0.0, 0.15, 0.4, 0.55), (300.0, 380.0, 380.0, 120.0))
TIMES = (0.0, 0.1, 0.2, 0.35, 0.6999, 0.7, 0.9)


@pytest.mark.parametrize("profile", [UP, DOWN, TABLE], ids=["up", "down", "table"])
def test_the_angle_is_the_integral_of_the_speed(profile):
    """Theta(t) against a quadrature of Omega (the kinks at the points as break points);
    agreement to the quadrature's tolerance, 1e-12 relative."""
    for t in TIMES:
        ref, _ = quad(profile.speed, 0.0, t, points=[x for x in profile.times if 0 < x < t],
                      limit=200, epsabs=0.0, epsrel=1e-13)
        assert profile.angle(t) == pytest.approx(ref, rel=1e-12, abs=1e-12), t


@pytest.mark.parametrize("profile", [UP, DOWN, TABLE], ids=["up", "down", "table"])
def test_the_acceleration_is_the_derivative_of_the_speed(profile):
    """dOmega/dt against a central difference of Omega away from the kinks: exact for a
    linear ramp up to the round-off of the difference (h = 1e-6 s: 1e-7 relative)."""
    h = 1e-6
    for t in (0.1, 0.3, 0.5, 0.69, 0.8):
        if min(abs(t - x) for x in profile.times) < 2 * h:
            continue
        fd = (profile.speed(t + h) - profile.speed(t - h)) / (2 * h)
        assert profile.acceleration(t) == pytest.approx(fd, rel=1e-7, abs=1e-6), t
    assert (UP.speed(0.0), UP.speed(10.0), UP.max_speed) == (100.0, 400.0, 400.0)
    assert (DOWN.max_speed, DOWN.max_acceleration) == (400.0, 1000.0)
    assert (TABLE.min_speed, TABLE.shortest_change) == (120.0, 0.15)


@pytest.mark.parametrize("profile", [UP, DOWN, TABLE], ids=["up", "down", "table"])
def test_at_a_point_the_acceleration_is_the_one_before_it(profile):
    """At each point the slope of the interval that ends there (a step's loads are its end's,
    and the step that ends on a ramp's last point is in the ramp): a backward difference of
    the speed (h = 1e-6 s), 0 at the first point."""
    h = 1e-6
    assert profile.acceleration(profile.times[0]) == 0.0
    for t in profile.times[1:]:
        back = (profile.speed(t) - profile.speed(t - h)) / h
        assert profile.acceleration(t) == pytest.approx(back, rel=1e-7, abs=1e-6), t


@pytest.mark.parametrize("profile", [UP, DOWN, TABLE], ids=["up", "down", "table"])
def test_a_profile_continued_from_any_time_keeps_the_angle_and_the_speed(profile):
    """``continued(t0, t1, w)`` (a host's speed input over a step): from t0 the speed goes
    linearly to w at t1 and stays; the angle is the original's up to t0 plus a quadrature
    of the new speed from t0; continued again at t1, the same from there."""
    for t0 in (0.1, 0.2, 0.6):
        w0, t1, t2 = profile.speed(t0), t0 + 0.05, t0 + 0.1
        once = profile.continued(t0, t1, 250.0)
        twice = once.continued(t1, t2, 260.0)
        assert once.speed(t0) == w0 and twice.speed(t2) == 260.0
        assert twice.times == (t1, t2)  # two points, whatever came before

        def speed(x, w0=w0, t0=t0, t1=t1, t2=t2):
            if x < t1:
                return w0 + (250.0 - w0) * (x - t0) / (t1 - t0)
            return 250.0 + 10.0 * (x - t1) / (t2 - t1) if x < t2 else 260.0

        for p, t in ((once, t0 + 0.02), (once, t1), (twice, t1), (twice, t0 + 0.08),
                     (twice, t0 + 0.3)):
            tail, _ = quad(speed, t0, t, points=[x for x in (t1, t2) if t0 < x < t],
                           epsabs=0.0, epsrel=1e-13)
            assert p.angle(t) == pytest.approx(profile.angle(t0) + tail, rel=1e-12), (t0, t)
    with pytest.raises(ValueError, match="later"):
        UP.continued(0.3, 0.3, 200.0)


def test_a_profile_must_be_one_that_can_turn_a_shaft():
    with pytest.raises(ValueError, match="needs a duration > 0 s"):
        SpeedProfile.ramp(100.0, 200.0, 0.0, 0.0)
    with pytest.raises(ValueError, match=r"speed -5\.0 rad/s at t = 1\.0 s"):
        SpeedProfile.ramp(100.0, -5.0, 0.0, 1.0)
    with pytest.raises(ValueError, match=r"t = 0\.1 s after t = 0\.2 s: the times"):
        SpeedProfile((0.0, 0.2, 0.1), (1.0, 2.0, 3.0))
    with pytest.raises(ValueError, match="starts at t = 0 s"):
        SpeedProfile((0.5, 1.0), (1.0, 2.0))
    assert not SpeedProfile.ramp(100.0, 100.0).varies


@pytest.mark.parametrize("profile", [UP, DOWN], ids=["up", "down"])
def test_the_unbalance_force_is_the_reaction_of_its_accelerated_mass(profile):
    """Two unbalances on shafts of signed ratios +1 and -0.25 (a gear turning the other way):
    at each time the force of the step's coefficients, in the compiled step's form
    (:func:`gear_fmu.loads.unbalance_force`), is ``-m e r''`` of the mass at ``e (cos phi,
    sin phi)``, phi = s Theta + phase, with r'' by a central difference of the position (h =
    1e-5 s: truncation (phi' h)^2 / 12 ~ 1.3e-6 relative at 400 rad/s, round-off 1e-16 / h^2
    ~ 1e-6: bound 2e-5 of the amplitude, margin 8)."""
    ub = Unbalances(node=np.array([3, 9]), me=np.array([2.0e-3, 5.0e-3]),
                    shaft=np.array([0, 1]), phase=np.array([0.4, -1.1]))
    signed = np.array([1.0, -0.25])
    h = 1e-5
    for t in (0.05, 0.3, 0.45, 0.65, 0.8):
        coef = accelerated_unbalance_coefficients(ub, signed, profile, t)
        force = unbalance_force(coef, t)
        for i in range(2):
            def position(tt, i=i):
                phi = signed[ub.shaft[i]] * profile.angle(tt) + ub.phase[i]
                return np.array([math.cos(phi), math.sin(phi)])
            accel = (position(t + h) - 2 * position(t) + position(t - h)) / h**2
            expected = -ub.me[i] * accel
            scale = ub.me[i] * (signed[i] * profile.speed(t)) ** 2
            np.testing.assert_allclose(force[i], expected, rtol=0, atol=2e-5 * scale,
                                       err_msg=f"t = {t}, unbalance {i}")
