"""The order spectrum of the bearing forces and the amplitudes of their known lines, on one
scale: the peak amplitude. A line ``A cos(2 pi q f_rot t + phi)`` reads ``A`` [unit of the
signal] at order ``q`` in :func:`order_spectrum` (every figure's spectrum, and the spectrum a
sweep point stores) and in :func:`order_lines` (the least-squares line amplitudes of the report
of ``gsb run``). The equation has its home in ``docs/equations.md`` ("Order spectrum").

Orders are cycles per revolution of a reference shaft (``rotation_hz``): for the bearing
forces of the paper's pinion shaft, 1 is once per pinion revolution and ``z1`` the mesh
frequency. The lines a train excites, every shaft's 1x and every mesh's harmonics, are those
of :func:`train_lines` (in revolutions of the input shaft; a bearing's figures and report read
them in revolutions of its own shaft).
"""

from __future__ import annotations

import numpy as np

__all__ = ["HARMONICS", "PAD", "WINDOWS", "line_amplitudes", "order_lines", "order_spectrum",
           "resolved_lines", "spectral_resolution", "train_lines"]

#: the mesh harmonics k = 1 .. HARMONICS of every mesh that the report and figures follow
HARMONICS = 3

#: the tapers :func:`order_spectrum` knows (the first is its default)
WINDOWS = ("hann", "rectangular")
#: zero padding of :func:`order_spectrum` (FFT length = PAD x samples): the peak of a line
#: between bins is missed by at most 1 / (2 PAD) bin, a loss below 0.26 % with the Hann window
PAD = 8


def _taper(window: str, n: int) -> np.ndarray:
    """Periodic Hann ``1/2 - 1/2 cos(2 pi j / n)`` (a line on a bin leaks into its two
    neighbours only, so lines on bins are read exactly) or ones."""
    if window == "hann":
        return 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(n) / n)
    if window == "rectangular":
        return np.ones(n)
    raise ValueError(f"window = {window!r}: must be one of {', '.join(WINDOWS)}")


def spectral_resolution(samples: int, dt: float, rotation_hz: float) -> float:
    """Order resolution ``1 / (samples dt rotation_hz)`` of a window of ``samples`` samples:
    one bin of the unpadded DFT, the inverse of the window's length in revolutions (the Hann
    main lobe is two resolutions wide on either side of a line)."""
    return 1.0 / (samples * dt * rotation_hz)


def order_spectrum(signal, dt: float, rotation_hz: float, *, window: str = "hann",
                   pad: int = PAD, max_order: float | None = None):
    """Single-sided spectrum of uniformly sampled signals against order, in peak amplitude.

    The mean ``xbar`` is removed, the rest tapered by ``w`` (periodic Hann by default, or
    rectangular), zero-padded to ``M = pad N`` samples and transformed; the amplitude at bin
    ``k`` is corrected by the window's coherent gain ``sum(w)``::

        A_k = 2 |sum_j w_j (x_j - xbar) exp(-2 pi i j k / M)| / sum_j w_j,
        q_k = k / (M dt rotation_hz),

    ``A_0 = |xbar|`` (the mean over the window), and the bin at the Nyquist frequency of an
    even ``M`` is halved (it has no negative-frequency twin). So a line
    ``A cos(2 pi q rotation_hz t + phi)`` reads ``A`` at order ``q``:

    * exactly (up to round-off) when the window holds a whole number of periods of it and of
      every other line (lines on bins);
    * otherwise within the scalloping loss of a line up to ``1 / (2 pad)`` bin off a padded
      bin (Hann, ``pad = 8``: 0.25 %) plus the tails of the other lines, its peak within half
      a padded bin of ``q``, if it lies three resolutions (:func:`spectral_resolution`) or
      more from order 0 and from lines of its size. Closer to order 0 the main lobes of its
      negative-frequency image and of the error of the mean overlap its own (errors of
      percents at one or two resolutions).

    The least-squares amplitudes of :func:`order_lines` are on the same scale, and exact there.
    The equation's home is docs/equations.md ("Order spectrum").

    Parameters
    ----------
    signal : array_like, shape (N, ...)
        Samples; trailing axes are independent signals.
    dt : float
        Sample spacing [s].
    rotation_hz : float
        Rotation frequency of the reference shaft [Hz]: order 1 is once per its revolution.
    window : {"hann", "rectangular"}
        Taper. Hann keeps a line's leakage within two resolutions
        (:func:`spectral_resolution`) of it; rectangular reads lines on bins exactly too but
        leaks far from lines between bins.
    pad : int
        Zero padding factor (>= 1).
    max_order : float, optional
        Keep the bins up to this order (default: up to the Nyquist order).

    Returns
    -------
    orders : numpy.ndarray, shape (m,)
        Orders [1 / revolution of the reference shaft].
    amplitudes : numpy.ndarray, shape (m, ...)
        Peak amplitudes, in the unit of ``signal``.

    Examples
    --------
    A mean of 2, a line of 3 at order 1 and of 0.5 at order 4, over two revolutions of 32
    samples each:

    >>> theta = np.arange(64) / 32  # revolutions
    >>> y = 2.0 + 3.0 * np.cos(2 * np.pi * theta + 0.4) + 0.5 * np.sin(2 * np.pi * 4 * theta)
    >>> q, a = order_spectrum(y, 1 / 32, 1.0, max_order=5)
    >>> q[[0, 1, 16, 64]].tolist()
    [0.0, 0.0625, 1.0, 4.0]
    >>> np.round(a[[0, 16, 64]], 12).tolist()
    [2.0, 3.0, 0.5]
    """
    x = np.asarray(signal, dtype=float)
    n = x.shape[0]
    if n < 2:
        raise ValueError(f"a spectrum needs at least 2 samples, got {n}")
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt = {dt!r} s: must be finite and > 0")
    if not (np.isfinite(rotation_hz) and rotation_hz > 0):
        raise ValueError(f"rotation_hz = {rotation_hz!r} Hz: must be finite and > 0")
    if int(pad) != pad or pad < 1:
        raise ValueError(f"pad = {pad!r}: must be an integer >= 1")
    w = _taper(window, n)
    mean = x.mean(axis=0)
    m = int(pad) * n
    tapered = (x - mean) * w.reshape((n,) + (1,) * (x.ndim - 1))
    amp = np.abs(np.fft.rfft(tapered, m, axis=0)) * (2.0 / w.sum())
    amp[0] = np.abs(mean)
    if m % 2 == 0:
        amp[-1] *= 0.5
    orders = np.arange(amp.shape[0]) / (m * dt * rotation_hz)
    if max_order is not None:
        keep = orders <= max_order * (1.0 + 1e-9)
        orders, amp = orders[keep], amp[keep]
    return orders, amp


def order_lines(time_s, signal, frequencies_hz) -> np.ndarray:
    """Amplitudes of sinusoidal lines at exactly known frequencies, by linear least squares.

    Fits ``c0 + sum_k a_k cos(2 pi f_k t) + b_k sin(2 pi f_k t)`` to the samples and returns
    ``hypot(a_k, b_k)``, the peak amplitude of each line (the scale of
    :func:`order_spectrum`). Unlike a DFT this needs no whole number of periods in the window
    (one gear revolution holds 157/26 = 6.04 pinion revolutions in the paper's case), only
    lines resolved by it (:func:`resolved_lines`).

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


def line_amplitudes(time_s, signal, frequencies_hz, duration_s: float,
                    dt_s: float) -> np.ndarray:
    """Peak amplitudes (n, ...) of the lines at ``frequencies_hz`` over a window of
    ``duration_s`` sampled every ``dt_s`` (:func:`order_lines` of the lines
    :func:`resolved_lines` keeps; NaN for the others, and for all when the window has too few
    samples to fit them)."""
    t = np.asarray(time_s, dtype=float)
    y = np.asarray(signal, dtype=float)
    f = np.atleast_1d(np.asarray(frequencies_hz, dtype=float))
    ok = resolved_lines(f, duration_s, dt_s)
    amplitudes = np.full((f.size, *y.shape[1:]), np.nan)
    if ok.any() and y.shape[0] >= 1 + 2 * ok.sum():
        amplitudes[ok] = order_lines(t, y, f[ok])
    return amplitudes


def train_lines(layout, harmonics: int = HARMONICS) -> tuple[np.ndarray, list[str]]:
    """The lines a gear train excites, in orders of its input shaft (cycles per input
    revolution) and their labels: each shaft's 1x (``<shaft>_1x``, its speed ratio to the
    input, :attr:`gear_fmu.layout.Layout.ratios`), then each mesh's harmonics of its mesh
    frequency (``<mesh>_GMF``, ``<mesh>_2GMF``, ...: ``k z_driver`` times its driver's ratio),
    k = 1 .. ``harmonics``, in the layout's order. Divide by a shaft's ratio for orders of that
    shaft.

    >>> from fmu_src.case import load_case
    >>> from fmu_src.description import layout
    >>> orders, labels = train_lines(layout(load_case("baguet2010_spur")))
    >>> labels
    ['pinion_shaft_1x', 'gear_shaft_1x', 'mesh_GMF', 'mesh_2GMF', 'mesh_3GMF']
    >>> [round(float(q), 4) for q in orders]
    [1.0, 0.1656, 26.0, 52.0, 78.0]
    """
    ratios = layout.ratios
    orders = [float(r) for r in ratios]
    labels = [f"{s.name}_1x" for s in layout.shafts]
    for mesh, (driver, _) in zip(layout.meshes, layout.drivers, strict=True):
        gear = layout.gear(driver)
        order = gear.teeth * float(ratios[layout.shaft_index[gear.shaft]])
        for k in range(1, harmonics + 1):
            orders.append(k * order)
            labels.append(f"{mesh.name}_{'' if k == 1 else k}GMF")
    return np.array(orders), labels
