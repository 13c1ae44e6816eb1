"""Order tracking of a run-up: the lines of a signal at fixed orders of a shaft whose speed
changes (``drive.speed_profile``, docs/equations.md "Run-ups").

At a varying speed a line is fixed in the shaft's angle, not in time: ``A cos(2 pi q r + phi)``
with ``r`` the shaft's revolutions and ``q`` the order. Both functions take the signal against
``r`` over windows of a few revolutions, each labelled by the shaft's mean speed there:
:func:`tracked_orders` fits the chosen orders by least squares
(:func:`orchestrator.analysis.spectrum.order_lines`, with revolutions for time and orders for
frequencies: exact for lines the window resolves, whatever the speed does inside it);
:func:`order_waterfall` resamples the signal on equal steps of angle and takes the order
spectrum of each window (:func:`orchestrator.analysis.spectrum.order_spectrum`, peak amplitude,
Hann window).
"""

from __future__ import annotations

import numpy as np

from orchestrator.analysis.spectrum import order_lines, order_spectrum

__all__ = ["order_waterfall", "tracked_orders", "windows"]


def windows(revolutions, length: float, hop: float) -> list[tuple[int, int]]:
    """``[(start, stop)]`` sample ranges of ``revolutions`` (increasing, (N,)): the samples in
    ``[s, s + length)`` revolutions, ``s`` every ``hop`` revolutions from the first sample
    while the data reach ``s + length``.

    >>> windows(np.arange(11) * 0.5, 2.0, 1.0)
    [(0, 4), (2, 6), (4, 8), (6, 10)]
    """
    r = np.asarray(revolutions, dtype=float)
    out = []
    start = r[0]
    while start + length <= r[-1] + 1e-9 * length:
        a = int(np.searchsorted(r, start - 1e-9 * length))
        b = int(np.searchsorted(r, start + length * (1 - 1e-9), side="right"))
        out.append((a, b))
        start += hop
    return out


def tracked_orders(revolutions, speed, signal, orders, length: float = 6.0,
                   hop: float = 1.5) -> dict:
    """Peak amplitudes of the lines at ``orders`` (cycles per revolution of the shaft) of
    ``signal`` (N, ...) sampled at the shaft's ``revolutions`` (N,) [-] while it turns at
    ``speed`` (N,) [rad/s], over windows of ``length`` revolutions every ``hop``
    (:func:`windows`). Returns ``speed`` (n_windows,) [rad/s] the mean speed in each window,
    ``revolution`` (n_windows,) its middle, ``amplitudes`` (n_windows, n_orders, ...) in the
    unit of ``signal`` (NaN for an order the window cannot separate from another or from 0:
    closer than 1.5 / ``length``; the others are fitted without it)."""
    r = np.asarray(revolutions, dtype=float)
    y = np.asarray(signal, dtype=float)
    w = np.asarray(speed, dtype=float)
    q = np.atleast_1d(np.asarray(orders, dtype=float))
    kept = [i for i in range(q.size)
            if min(abs(q[i]), *(abs(q[i] - q[j]) for j in range(q.size) if j != i))
            * length >= 1.5]
    spans = windows(r, length, hop)
    out = np.full((len(spans), q.size, *y.shape[1:]), np.nan)
    if kept:
        for k, (a, b) in enumerate(spans):
            out[k, kept] = order_lines(r[a:b], y[a:b], q[kept])
    return {"speed": np.array([w[a:b].mean() for a, b in spans]),
            "revolution": np.array([0.5 * (r[a] + r[b - 1]) for a, b in spans]),
            "amplitudes": out}


def order_waterfall(revolutions, speed, signal, length: float = 6.0, hop: float = 1.5,
                    per_revolution: int = 256, max_order: float | None = None) -> dict:
    """The order spectrum of ``signal`` (N,) over windows of ``length`` revolutions every
    ``hop`` (:func:`windows`), the signal resampled linearly on ``per_revolution`` equal steps
    of the shaft's angle (``revolutions`` (N,), increasing). Returns ``orders`` (m,) [cycles
    per revolution], ``speed`` (n_windows,) [rad/s] the mean speed of each window and
    ``amplitudes`` (n_windows, m) [unit of the signal] (peak amplitude, Hann window,
    :func:`orchestrator.analysis.spectrum.order_spectrum`), up to ``max_order``."""
    r = np.asarray(revolutions, dtype=float)
    y = np.asarray(signal, dtype=float)
    w = np.asarray(speed, dtype=float)
    rows, speeds, orders = [], [], None
    steps = np.arange(round(length * per_revolution)) / per_revolution
    for a, b in windows(r, length, hop):
        orders, amp = order_spectrum(np.interp(r[a] + steps, r, y), 1.0 / per_revolution, 1.0,
                                     max_order=max_order)
        rows.append(amp)
        speeds.append(w[a:b].mean())
    if orders is None:
        return {"orders": np.zeros(0), "speed": np.zeros(0), "amplitudes": np.zeros((0, 0))}
    return {"orders": orders, "speed": np.array(speeds), "amplitudes": np.array(rows)}
