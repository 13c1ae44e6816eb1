"""The closed forms of Newmark's period error and detuned response
(:mod:`orchestrator.run.checks`) against a Newmark integration of one oscillator written out
here."""

import math

import numpy as np
import pytest

from orchestrator.run.checks import (
    PERIOD_ERROR_LIMIT,
    newmark_period_error,
    newmark_resonance_response,
    steps_for_period_error,
)


def newmark(omega, zeta, dt, n, force=None):
    """Average-acceleration Newmark (gamma 1/2, beta 1/4) on x'' + 2 zeta omega x' + omega^2 x
    = f(t), from x = 1, v = 0 (free) or rest (forced); returns x at the n + 1 instants."""
    f = (lambda t: 0.0) if force is None else force
    x, v = (1.0, 0.0) if force is None else (0.0, 0.0)
    a = f(0.0) - 2 * zeta * omega * v - omega**2 * x
    out = [x]
    lhs = 1.0 + zeta * omega * dt + omega**2 * dt**2 / 4
    for i in range(n):
        t = (i + 1) * dt
        xp = x + dt * v + dt**2 / 4 * a
        vp = v + dt / 2 * a
        a = (f(t) - 2 * zeta * omega * vp - omega**2 * xp) / lhs
        x, v = xp + dt**2 / 4 * a, vp + dt / 2 * a
        out.append(x)
    return np.array(out)


@pytest.mark.parametrize("steps", [4.9, 9.86, 18.2, 40.0])
def test_period_error_is_the_one_an_undamped_newmark_oscillator_shows(steps):
    """The period measured from the zero crossings of a free undamped oscillator integrated
    with Newmark over 200 periods equals T (1 + newmark_period_error)."""
    omega = 2 * math.pi
    dt = 1.0 / steps
    x = newmark(omega, 0.0, dt, int(200 * steps * 1.2))
    up = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    times = (up + x[up] / (x[up] - x[up + 1])) * dt  # linear interpolation of the crossing
    measured = (times[-1] - times[0]) / (up.size - 1)
    assert abs(measured - (1 + newmark_period_error(steps))) < 1e-3 * newmark_period_error(steps)
    assert np.abs(x).max() <= 1 + 1e-9  # no growth, and (below) no numerical damping
    assert np.abs(x[-int(2 * steps):]).max() > 0.99


@pytest.mark.parametrize("steps, zeta", [(9.86, 0.065), (4.9, 0.065), (20.0, 0.1)])
def test_resonance_response_is_the_steady_amplitude_newmark_gives(steps, zeta):
    """A forcing at the mode's own frequency: the steady amplitude of the Newmark run over the
    exact one, 1 / (2 zeta), equals newmark_resonance_response."""
    omega = 2 * math.pi
    dt = 1.0 / steps
    n = int(steps * 60 / zeta)  # the start transient decays by exp(-2 pi zeta 30 / zeta)
    x = newmark(omega, zeta, dt, n, force=lambda t: omega**2 * math.sin(omega * t))
    tail = x[-int(10 * steps):]
    # the amplitude from the samples: a least-squares fit of sin and cos at omega
    t = np.arange(x.size)[-tail.size:] * dt
    basis = np.column_stack([np.sin(omega * t), np.cos(omega * t)])
    amplitude = float(np.hypot(*np.linalg.lstsq(basis, tail, rcond=None)[0]))
    expected = newmark_resonance_response(steps, zeta) / (2 * zeta)
    assert amplitude == pytest.approx(expected, rel=1e-6)


def test_steps_for_the_limit():
    """About 18 steps per period keep the period error at 1 % (the series
    (omega dt)^2 / 12 gives pi / sqrt(0.03) = 18.1)."""
    n = steps_for_period_error()
    assert newmark_period_error(n) == pytest.approx(PERIOD_ERROR_LIMIT, rel=1e-9)
    assert n == pytest.approx(math.pi / math.sqrt(3 * PERIOD_ERROR_LIMIT), rel=0.01)
