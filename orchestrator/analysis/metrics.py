"""Post-processing of runs: steady-state window, dynamic tooth load factor, bearing-load
peak-to-peak, orbit ellipse fit (paper Sec. 4, Figs. 7-11, 14) and the report of ``gsb run``
(:func:`run_report`, with the order lines of the bearing loads from
:mod:`orchestrator.analysis.spectrum`).

Pure functions on arrays from a results file (:func:`orchestrator.run.results.read_results`).
"""

from __future__ import annotations

import math

import numpy as np

from fmu_src.case import Case
from fmu_src.description import gear_pairs, layout, mesh_teeth
from orchestrator.analysis.spectrum import line_amplitudes, pinion_lines

__all__ = ["fit_ellipse", "run_metrics", "run_report", "static_mesh_load", "steady_window",
           "stored_case"]


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
    from fmu_src.case import parse_case, parse_toml

    where = f"{attrs.get('case_file', 'results') if source is None else source} (stored case)"
    return parse_case(parse_toml(str(attrs["case_toml"]), where), where)


def _static_load(results: dict) -> float:
    """Static load [N] of the first mesh of the case stored in a results file
    (:func:`stored_case`): the torque on its driver's shaft over its base radius.
    TODO(train): the mesh_force channel of one mesh, the dynamic factor of each."""
    case = stored_case(results["attrs"])
    lay = layout(case)
    pair = gear_pairs(case)[0]
    torque = lay.torque_on(lay.gear(lay.drivers[0][0]).shaft)
    return static_mesh_load(torque, pair.base_radius[0], pair.base_helix_angle)


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


def run_report(results: dict) -> dict:
    """Figures of ``gsb run`` over the last gear revolution (the last half of a shorter run).

    Returns ``dynamic_factor`` (R, the maximum mesh force in the window over the static load
    ``T / (r_b1 cos(beta_b))``), ``bearing_force_ptp`` (4,) the peak-to-peak of ||F_b|| [N],
    ``line_amplitudes`` (4, n) the peak amplitudes [N] of the lines of ||F_b||
    (:func:`~orchestrator.analysis.spectrum.line_amplitudes`: least squares, NaN for a line
    the window does not resolve; the scale of the order spectrum of every figure) at
    ``line_orders`` (n,) pinion orders named ``line_labels``
    (:func:`~orchestrator.analysis.spectrum.pinion_lines`),
    ``window_s`` (2,) [s] the window's start and end (it holds the steps ending after the
    start) and ``window_kind`` ("last gear revolution" or "last half of the run").
    """
    time_s = np.asarray(results["time"], dtype=float)
    if time_s.size < 2:
        raise ValueError(f"a report needs at least 2 time steps, got {time_s.size}")
    case = stored_case(results["attrs"])
    teeth = mesh_teeth(case)[0]  # TODO(train): the lines and window of a single pair
    pinion_hz = abs(case["drive.speed"]) / (2.0 * np.pi)
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
    dt_s = (end_s - time_s[0]) / (time_s.size - 1)
    amplitudes = line_amplitudes(time_s[win], norm, orders * pinion_hz, duration, dt_s)
    return {
        "dynamic_factor": float(np.max(results["mesh_force"][win]) / _static_load(results)),
        "bearing_force_ptp": np.ptp(norm, axis=0),
        "line_amplitudes": np.ascontiguousarray(amplitudes.T),
        "line_orders": orders,
        "line_labels": labels,
        "window_s": np.array([end_s - duration, end_s]),
        "window_kind": kind,
    }
