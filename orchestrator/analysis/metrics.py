"""Post-processing of runs: steady-state window, dynamic tooth load factor, bearing-load
peak-to-peak, orbit ellipse fit (paper Sec. 4, Figs. 7-11, 14), order lines of the bearing
loads and the report of ``gsb run`` (:func:`run_report`).

Pure functions on arrays from a results file (:func:`orchestrator.run.results.read_results`).
"""

from __future__ import annotations

import math

import numpy as np

from fmu_src.case import Case
from fmu_src.description import gear_pair

__all__ = ["fit_ellipse", "order_amplitude_spectrum", "order_lines", "order_spectrum",
           "pinion_lines", "resolved_lines", "run_metrics", "run_report", "static_mesh_load",
           "steady_window", "stored_case"]


def steady_window(time: np.ndarray, duration: float) -> np.ndarray:
    """Boolean mask of the steps ending in the last ``duration`` seconds of a run (all of them
    if the run is shorter): ``duration / dt`` samples."""
    time = np.asarray(time)
    return time > time[-1] - duration * (1 - 1e-9)


def static_mesh_load(torque: float, base_radius: float, base_helix_angle: float = 0.0) -> float:
    """Normal mesh load balancing the input torque, ``T / (r_b1 cos(beta_b))`` [N]."""
    return abs(torque) / (base_radius * math.cos(base_helix_angle))


def stored_case(attrs: dict, source: str | None = None) -> Case:
    """The case a results file was run with (root attribute ``case_toml``, the effective case
    after the overrides, bit for bit); ``source`` names it in error messages (default: the
    case file it was read from)."""
    import tomllib

    from fmu_src.case import parse_case

    where = attrs.get("case_file", "results") if source is None else source
    return parse_case(tomllib.loads(str(attrs["case_toml"])), f"{where} (stored case)")


def _static_load(results: dict) -> float:
    """Static mesh load [N] of the case stored in a results file (:func:`stored_case`)."""
    case = stored_case(results["attrs"])
    pair = gear_pair(case)
    return static_mesh_load(case["operation.torque"], pair.base_radius[0],
                            pair.base_helix_angle)


def fit_ellipse(x, y) -> dict:
    """Least-squares ellipse through points (Fitzgibbon, Pilu & Fisher 1999, direct method).

    Returns ``centre`` (2,), semi-axes ``axes`` (major, minor) and the major axis ``angle`` [rad]
    (Fig. 9: the orbit centre gives the mean eccentricity). Coordinates are centred and scaled
    first for conditioning.

    Examples
    --------
    >>> t = np.linspace(0, 2 * np.pi, 50)
    >>> e = fit_ellipse(3 + 2 * np.cos(t), -1 + 0.5 * np.sin(t))
    >>> np.round(e["centre"], 12).tolist(), np.round(e["axes"], 12).tolist()
    ([3.0, -1.0], [2.0, 0.5])
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.size < 6:
        raise ValueError(f"an ellipse fit needs at least 6 points, got {x.size}")
    mx, my = x.mean(), y.mean()
    sc = max(np.ptp(x), np.ptp(y), 1e-300)
    u, v = (x - mx) / sc, (y - my) / sc
    d1 = np.column_stack([u * u, u * v, v * v])
    d2 = np.column_stack([u, v, np.ones_like(u)])
    s1, s2, s3 = d1.T @ d1, d1.T @ d2, d2.T @ d2
    t = -np.linalg.solve(s3, s2.T)
    m = s1 + s2 @ t
    m = np.array([m[2] / 2, -m[1], m[0] / 2])
    _, vec = np.linalg.eig(m)
    vec = np.real(vec)
    cond = 4 * vec[0] * vec[2] - vec[1] ** 2
    ok = np.flatnonzero(cond > 0)
    if ok.size == 0:
        raise ValueError("the points do not lie on an ellipse")
    a1 = vec[:, ok[0]]
    a, b, c = a1
    d, e, f = t @ a1
    den = b * b - 4 * a * c
    x0 = (2 * c * d - b * e) / den
    y0 = (2 * a * e - b * d) / den
    # semi-axes from the centred quadratic form
    g = a * x0 * x0 + b * x0 * y0 + c * y0 * y0 + d * x0 + e * y0 + f
    lam, rot = np.linalg.eigh(np.array([[a, b / 2], [b / 2, c]]))
    axes = np.sqrt(-g / lam)
    order = np.argsort(axes)[::-1]
    major = rot[:, order[0]]
    return {"centre": np.array([mx + sc * x0, my + sc * y0]), "axes": sc * axes[order],
            "angle": math.atan2(major[1], major[0])}


def run_metrics(results: dict, steady: float) -> dict:
    """Figures of one run over its last ``steady`` seconds.

    Returns ``R`` (max dynamic over static mesh load, Sec. 4.2.2), ``force_ptp`` (4,) the
    peak-to-peak of ||F_b|| [N] (Fig. 8b-c), ``force_mean`` (4,) [N], ``orbit_centre`` (4, 2)
    [m] (ellipse fit, Fig. 9, 14) and ``orbit_mean`` (4, 2) [m].
    """
    win = steady_window(results["time"], steady)
    w0 = _static_load(results)
    fb = np.hypot(results["bearing_force"][win, :, 0], results["bearing_force"][win, :, 1])
    journal = results["journal_position"][win]
    centres = []
    for b in range(journal.shape[1]):
        try:
            centres.append(fit_ellipse(journal[:, b, 0], journal[:, b, 1])["centre"])
        except (ValueError, np.linalg.LinAlgError):
            centres.append(journal[:, b].mean(axis=0))
    return {
        "R": float(results["mesh_force"][win].max() / w0),
        "force_ptp": np.ptp(fb, axis=0),
        "force_mean": fb.mean(axis=0),
        "orbit_centre": np.array(centres),
        "orbit_mean": journal.mean(axis=0),
    }


def order_lines(time_s, signal, frequencies_hz) -> np.ndarray:
    """Amplitudes of sinusoidal lines at exactly known frequencies, by linear least squares.

    Fits ``c0 + sum_k a_k cos(2 pi f_k t) + b_k sin(2 pi f_k t)`` to the samples and returns
    ``hypot(a_k, b_k)``, the peak amplitude of each line. Unlike a DFT this needs no whole
    number of periods in the window (one gear revolution holds 157/26 = 6.04 pinion
    revolutions in the paper's case), only lines resolved by it (:func:`resolved_lines`).

    Parameters
    ----------
    time_s : array_like, shape (N,)
        Sample times [s] (any spacing).
    signal : array_like, shape (N, ...)
        Samples; trailing axes are independent signals fitted at once.
    frequencies_hz : array_like, shape (n,)
        Line frequencies [Hz].

    Returns
    -------
    numpy.ndarray, shape (n, ...)
        Peak amplitudes, in the unit of ``signal``.

    Examples
    --------
    >>> t = np.arange(1000) * 1e-3
    >>> y = 2.0 + 3.0 * np.cos(2 * np.pi * 7.3 * t + 0.4) + 0.5 * np.sin(2 * np.pi * 50 * t)
    >>> np.round(order_lines(t, y, [7.3, 50.0]), 12).tolist()
    [3.0, 0.5]
    """
    t = np.asarray(time_s, dtype=float)
    y = np.asarray(signal, dtype=float)
    f = np.atleast_1d(np.asarray(frequencies_hz, dtype=float))
    if t.ndim != 1 or y.shape[:1] != t.shape:
        raise ValueError(f"time_s has shape {t.shape}, signal {y.shape}: need (N,) and (N, ...)")
    n, unknowns = f.size, 1 + 2 * f.size
    if t.size < unknowns:
        raise ValueError(f"{t.size} samples cannot fit a mean and {n} lines: need at least "
                         f"{unknowns}")
    # phases from the first sample: smaller arguments, same amplitudes
    arg = 2.0 * np.pi * np.outer(t - t[0], f)
    design = np.column_stack([np.ones_like(t), np.cos(arg), np.sin(arg)])
    coef, _, rank, _ = np.linalg.lstsq(design, y.reshape(t.size, -1), rcond=None)
    if rank < unknowns:
        raise ValueError(f"lines at {f.tolist()} Hz are not separable over "
                         f"{t[-1] - t[0]:.6g} s: rank {rank} of {unknowns}")
    return np.hypot(coef[1:n + 1], coef[n + 1:]).reshape((n, *y.shape[1:]))


def resolved_lines(frequencies_hz, duration_s: float, dt_s: float) -> np.ndarray:
    """Which lines a window of ``duration_s`` sampled every ``dt_s`` resolves (boolean mask).

    A line is resolved if the window holds at least one of its periods, it lies below the
    Nyquist frequency ``1 / (2 dt_s)``, and it is at least ``1 / duration_s`` away from every
    resolved line before it (Rayleigh). Lines outside this are left out of the fit: over a
    shorter window they are indistinguishable from the mean or from each other.

    >>> resolved_lines([1.0, 0.5, 1.2, 10.0, 60.0], 2.0, 0.01).tolist()
    [True, True, False, True, False]
    """
    f = np.atleast_1d(np.asarray(frequencies_hz, dtype=float))
    tol = 1.0 - 1e-9  # one gear revolution holds exactly one gear period, up to round-off
    ok = (np.abs(f) * duration_s >= tol) & (np.abs(f) * 2.0 * dt_s < 1.0)
    for k in range(f.size):
        if ok[k] and np.any(ok[:k] & (np.abs(f[:k] - f[k]) * duration_s < tol)):
            ok[k] = False
    return ok


def pinion_lines(teeth, harmonics: int = 3) -> tuple[np.ndarray, list[str]]:
    """Orders (in pinion revolutions) and labels of the reported lines: pinion 1x, gear 1x
    (``z1 / z2``) and the mesh orders ``k z1``, k = 1 .. ``harmonics``.

    >>> pinion_lines([26, 157])[1]
    ['1x', 'gear_1x', '26x', '52x', '78x']
    """
    z1, z2 = (int(z) for z in teeth)
    orders = np.array([1.0, z1 / z2] + [float(k * z1) for k in range(1, harmonics + 1)])
    return orders, ["1x", "gear_1x"] + [f"{k * z1}x" for k in range(1, harmonics + 1)]


def run_report(results: dict) -> dict:
    """Figures of ``gsb run`` over the last gear revolution (the last half of a shorter run).

    Returns ``dynamic_factor`` (R, the maximum mesh force in the window over the static load
    ``T / (r_b1 cos(beta_b))``), ``bearing_force_ptp`` (4,) the peak-to-peak of ||F_b|| [N],
    ``line_amplitudes`` (4, n) the peak amplitudes [N] of the lines of ||F_b||
    (:func:`order_lines`; NaN for a line the window does not resolve, :func:`resolved_lines`)
    at ``line_orders`` (n,) pinion orders named ``line_labels`` (:func:`pinion_lines`),
    ``window_s`` (2,) [s] the window's start and end (it holds the steps ending after the
    start) and ``window_kind`` ("last gear revolution" or "last half of the run").
    """
    time_s = np.asarray(results["time"], dtype=float)
    if time_s.size < 2:
        raise ValueError(f"a report needs at least 2 time steps, got {time_s.size}")
    values = stored_case(results["attrs"]).values
    teeth = values["gear_pair.teeth"]
    pinion_hz = abs(values["operation.speed"]) / (2.0 * np.pi)
    gear_rev_s = teeth[1] / (teeth[0] * pinion_hz)
    end_s = float(time_s[-1])
    if end_s >= gear_rev_s * (1.0 - 1e-9):
        duration, kind = gear_rev_s, "last gear revolution"
    else:
        duration, kind = 0.5 * end_s, "last half of the run"
    win = steady_window(time_s, duration)
    force = np.asarray(results["bearing_force"], dtype=float)[win]
    norm = np.hypot(force[..., 0], force[..., 1])
    orders, labels = pinion_lines(teeth)
    freqs = orders * pinion_hz
    ok = resolved_lines(freqs, duration, (end_s - time_s[0]) / (time_s.size - 1))
    amplitudes = np.full((norm.shape[1], orders.size), np.nan)
    if ok.any() and norm.shape[0] >= 1 + 2 * ok.sum():
        amplitudes[:, ok] = order_lines(time_s[win], norm, freqs[ok]).T
    return {
        "dynamic_factor": float(np.max(results["mesh_force"][win]) / _static_load(results)),
        "bearing_force_ptp": np.ptp(norm, axis=0),
        "line_amplitudes": amplitudes,
        "line_orders": orders,
        "line_labels": labels,
        "window_s": np.array([end_s - duration, end_s]),
        "window_kind": kind,
    }


def order_amplitude_spectrum(signal, dt: float, rotation_hz: float, pad: int = 8):
    """Peak-amplitude spectrum of uniformly sampled signals against order, for windows that
    are not a whole number of periods: the mean removed, a Hann window, zero-padded ``pad``
    times; amplitudes ``2 |X_k| / sum(w)``, so a line ``A cos(...)`` reads about ``A`` at its
    peak (the padding bounds the scalloping loss).

    Returns ``(orders, amplitudes)``, orders = f / ``rotation_hz``, amplitudes (m, ...) in the
    unit of ``signal`` (trailing axes are independent signals).
    """
    x = np.asarray(signal, dtype=float)
    n = x.shape[0]
    if n < 2:
        raise ValueError(f"a spectrum needs at least 2 samples, got {n}")
    w = np.hanning(n + 2)[1:-1]  # no zero end points
    x = (x - x.mean(axis=0)) * w.reshape((n,) + (1,) * (x.ndim - 1))
    nfft = 1 << math.ceil(math.log2(max(pad, 1) * n))
    amp = np.abs(np.fft.rfft(x, nfft, axis=0)) * (2.0 / w.sum())
    return np.fft.rfftfreq(nfft, dt) / rotation_hz, amp


def order_spectrum(signal, samples_per_revolution: float, max_order: float | None = None):
    """Single-sided peak-amplitude spectrum of uniformly sampled signals against order.

    The DFT of the whole window (no taper): bin ``k`` is the order ``k samples_per_revolution /
    N`` (cycles per revolution of the reference shaft), its amplitude ``2 |X_k| / N`` (``|X_0| /
    N``, the mean, at order 0, and at the Nyquist bin of an even ``N``), so a line
    ``A cos(2 pi q theta + phi)`` whose order ``q`` falls on a bin (a window of a whole number of
    its periods, e.g. of revolutions for integer orders) reads ``A`` exactly.

    Parameters
    ----------
    signal : array_like, shape (N, ...)
        Samples; trailing axes are independent signals.
    samples_per_revolution : float
        Samples per revolution of the reference shaft (the resolution is
        ``samples_per_revolution / N`` orders).
    max_order : float, optional
        Keep the bins up to this order (default: up to the Nyquist order).

    Returns
    -------
    orders : numpy.ndarray, shape (m,)
    amplitudes : numpy.ndarray, shape (m, ...)
        In the unit of ``signal``.

    Examples
    --------
    >>> theta = np.arange(64) / 32  # two revolutions, 32 samples each
    >>> y = 2.0 + 3.0 * np.cos(2 * np.pi * theta + 0.4) + 0.5 * np.sin(2 * np.pi * 4 * theta)
    >>> q, a = order_spectrum(y, 32, max_order=5)
    >>> q.tolist()
    [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 4.5, 5.0]
    >>> np.round(a[[0, 2, 8]], 12).tolist()
    [2.0, 3.0, 0.5]
    """
    x = np.asarray(signal, dtype=float)
    n = x.shape[0]
    if n < 2:
        raise ValueError(f"a spectrum needs at least 2 samples, got {n}")
    if not samples_per_revolution > 0:
        raise ValueError(f"samples_per_revolution = {samples_per_revolution!r} must be > 0")
    amp = np.abs(np.fft.rfft(x, axis=0)) * (2.0 / n)
    amp[0] *= 0.5
    if n % 2 == 0:
        amp[-1] *= 0.5
    orders = np.arange(amp.shape[0]) * (samples_per_revolution / n)
    if max_order is not None:
        keep = orders <= max_order * (1.0 + 1e-12)
        orders, amp = orders[keep], amp[keep]
    return orders, amp
