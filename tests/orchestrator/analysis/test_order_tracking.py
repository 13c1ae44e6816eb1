"""Order tracking (orchestrator.analysis.order_tracking) against signals built with known lines
at fixed orders of a shaft that accelerates."""

import numpy as np
import pytest

from gear_fmu.speed_profile import SpeedProfile
from orchestrator.analysis.order_tracking import order_waterfall, tracked_orders, windows

PROFILE = SpeedProfile.ramp(100.0, 400.0, t_start=0.0, duration=1.0)
LINES = {1.0: 3.0, 2.5: 0.4, 26.0: 0.7}  # order: peak amplitude


def _signal(samples_per_rev: int):
    """||F|| of a shaft run up 100 -> 400 rad/s over 1 s, sampled at equal times, the lines
    of LINES fixed in its angle (phases 0.3 q), a mean of 5, and a drift at order 0.0 that
    no line resolves."""
    revs_end = PROFILE.angle(1.0) / (2 * np.pi)
    t = np.linspace(0.0, 1.0, int(samples_per_rev * revs_end))
    r = np.array([PROFILE.angle(x) for x in t]) / (2 * np.pi)
    w = np.array([PROFILE.speed(x) for x in t])
    y = 5.0 + sum(a * np.cos(2 * np.pi * q * r + 0.3 * q) for q, a in LINES.items())
    return r, w, y


def test_tracked_lines_read_their_amplitudes_whatever_the_speed_does():
    """Least squares in the angle domain: each line's amplitude in every window to 1e-9
    (round-off of the fit), each window labelled by its mean speed (the speed rises); an
    order too close to another for the window (1.5 / length) is NaN, the others still
    exact."""
    r, w, y = _signal(400)
    out = tracked_orders(r, w, y, list(LINES), length=2.0, hop=0.5)
    assert out["amplitudes"].shape[1] == 3 and out["speed"].size > 70
    np.testing.assert_allclose(out["amplitudes"], np.broadcast_to(list(LINES.values()),
                                                                  out["amplitudes"].shape),
                               rtol=1e-9)
    assert np.all(np.diff(out["speed"]) > 0)
    close = tracked_orders(r, w, y, [1.0, 1.5, 26.0], length=2.0, hop=0.5)["amplitudes"]
    assert np.isnan(close[:, :2]).all()  # 0.5 apart: need 3 revolutions
    np.testing.assert_allclose(close[:, 2], 0.7, rtol=0.02)  # 1 and 2.5 not fitted: leakage


def test_the_waterfall_reads_each_line_at_its_order():
    """Resampled on equal angles (1024 per revolution from 2000 samples per revolution at the
    end of the ramp: linear interpolation loses (2 pi q / n)^2 / 8 = 1.3e-3 at order 26),
    windows of whole revolutions put the lines on bins: each reads its amplitude within
    0.5 % (measured 0.13 % at order 26, 1e-5 below), at its order."""
    r, w, y = _signal(2000)
    fall = order_waterfall(r, w, y, length=2.0, hop=2.0, per_revolution=1024, max_order=30.0)
    for q, a in LINES.items():
        k = int(np.argmin(np.abs(fall["orders"] - q)))
        assert fall["orders"][k] == pytest.approx(q, abs=1e-9)
        np.testing.assert_allclose(fall["amplitudes"][:, k], a, rtol=5e-3, err_msg=f"order {q}")
    assert windows(np.arange(11) * 0.5, 2.0, 1.0)[-1] == (6, 10)
