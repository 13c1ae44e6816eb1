"""Post-processing of runs: steady-state window, dynamic tooth load factor of each mesh,
bearing-load peak-to-peak, orbit ellipse fit (paper Sec. 4, Figs. 7-11, 14) and the report of
``gsb run`` (:func:`run_report`, with the order lines of the bearing loads from
:mod:`orchestrator.analysis.spectrum`), for any gear train: the bearings and meshes are those of
the case stored with the results (:func:`stored_case`), in its order.

Pure functions on arrays from a results file (:func:`orchestrator.run.results.read_results`).
"""

from __future__ import annotations

import math

import numpy as np

from fmu_src.case import Case
from fmu_src.description import gear_pairs, layout, speed_profile
from orchestrator.analysis.spectrum import line_amplitudes, train_lines

__all__ = ["fit_ellipse", "report_window", "run_metrics", "run_report", "static_mesh_load",
           "static_mesh_loads", "steady_window", "stored_case", "window_duration"]


def steady_window(time: np.ndarray, duration: float) -> np.ndarray:
    """Boolean mask of the steps ending in the last ``duration`` seconds of a run (all of them
    if the run is shorter): ``duration / dt`` samples."""
    time = np.asarray(time)
    return time > time[-1] - duration * (1 - 1e-9)


def static_mesh_load(torque: float, base_radius: float, base_helix_angle: float = 0.0) -> float:
    """Normal mesh load balancing the input torque, ``T / (r_b1 cos(beta_b))`` [N]."""
    return abs(torque) / (base_radius * math.cos(base_helix_angle))


def stored_case(attrs: dict, source: str | None = None, window: str | None = None) -> Case:
    """The case a results file was run with (root attribute ``case_toml``, the effective case
    after the overrides, bit for bit); ``source`` names it in error messages (default: the
    case file it was read from); ``window``: its ``simulation.window`` replaced (what a
    report of the stored run over another window takes)."""
    from fmu_src.case import parse_case, parse_toml

    where = f"{attrs.get('case_file', 'results') if source is None else source} (stored case)"
    case = parse_case(parse_toml(str(attrs["case_toml"]), where), where)
    if window is None or case["simulation.window"] == window:
        return case
    return case.with_overrides({"simulation.window": window})


def static_mesh_loads(case: Case) -> np.ndarray:
    """The static load of each mesh [N] (the case's mesh order): the torque its driver's
    shaft transmits (:meth:`gear_fmu.layout.Layout.torque_on`) over the driver's base radius
    and the cosine of the base helix angle (:func:`static_mesh_load`)."""
    lay = layout(case)
    return np.array([static_mesh_load(lay.torque_on(lay.gear(driver).shaft),
                                      pair.base_radius[0], pair.base_helix_angle)
                     for (driver, _), pair in zip(lay.drivers, gear_pairs(case), strict=True)])


def report_window(case: Case, time_s) -> tuple[float, str]:
    """The window of the report and the figures of a run ending at ``time_s[-1]`` [s]: the
    case's ``simulation.window`` (:func:`fmu_src.units.parse_window`: mesh periods of the
    fastest mesh, seconds or revolutions of a named shaft), by default the last revolution
    of the train's slowest shaft (the paper's: the last gear revolution, which holds a whole
    number of mesh periods of its mesh and of every shaft's 1x of a single stage), or the
    last half of the run when it is shorter. Returns its duration [s] and its name ("last
    revolution of the slowest shaft gear_shaft", "last 26 mesh periods", "last half of the
    run"). ValueError for a given window longer than the run.
    """
    end_s = float(np.asarray(time_s)[-1])
    duration, name = window_duration(case)
    shorter = duration is None or end_s < duration * (1.0 - 1e-9)
    if shorter and not case["simulation.window"]:
        return 0.5 * end_s, "last half of the run"
    if shorter:
        raise ValueError(f"simulation.window = {case['simulation.window']!r} ({duration:.4g} s) "
                         f"is longer than the run ({end_s:.4g} s): shorten it, or lengthen "
                         f"the run (simulation.mesh_periods)")
    return duration, name


def window_duration(case: Case) -> tuple[float | None, str]:
    """The duration [s] and the name of the case's window (:func:`report_window`), whatever
    the run's length (None and "" for the default rule without a revolution: a train at
    rest)."""
    from fmu_src.description import mesh_period
    from fmu_src.units import parse_window

    lay = layout(case)
    window = parse_window(case["simulation.window"])
    if window is None:
        k = int(np.argmin(lay.ratios))
        revolution = 2.0 * math.pi / (abs(lay.drive.speed) * float(lay.ratios[k]))
        if not math.isfinite(revolution):
            return None, ""
        return revolution, f"last revolution of the slowest shaft {lay.shafts[k].name}"
    count, unit, shaft = window
    if unit == "time":
        return count, f"last {count:g} s"
    if unit == "periods":
        return count * mesh_period(case), f"last {count:g} mesh periods"
    ratio = float(lay.ratios[lay.shaft_index[shaft]])
    plural = "" if count == 1 else "s"
    return (count * 2.0 * math.pi / (abs(lay.drive.speed) * ratio),
            f"last {count:g} revolution{plural} of {shaft}")


def _per_mesh(results: dict, name: str, win) -> np.ndarray:
    """A mesh channel in the window as (steps, n_meshes) (a file of an earlier version
    holds one mesh's as (steps,))."""
    values = np.asarray(results[name], dtype=float)
    return values.reshape(values.shape[0], -1)[win]


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

    Returns ``R`` (n_meshes,) the dynamic factor of each mesh (max dynamic over its static
    load, Sec. 4.2.2), ``transmission_error_ptp`` (n_meshes,) [m], ``force_ptp`` (nb,) the
    peak-to-peak of ||F_b|| [N] (Fig. 8b-c), ``force_mean`` (nb,) [N], ``orbit_centre``
    (nb, 2) [m] (ellipse fit, Fig. 9, 14) and ``orbit_mean`` (nb, 2) [m]; bearings and meshes
    in the order of the stored case.
    """
    win = steady_window(results["time"], steady)
    w0 = static_mesh_loads(stored_case(results["attrs"]))
    fb = np.hypot(results["bearing_force"][win, :, 0], results["bearing_force"][win, :, 1])
    journal = results["journal_position"][win]
    centres = []
    for b in range(journal.shape[1]):
        try:
            centres.append(fit_ellipse(journal[:, b, 0], journal[:, b, 1])["centre"])
        except (ValueError, np.linalg.LinAlgError):
            centres.append(journal[:, b].mean(axis=0))
    return {
        "R": _per_mesh(results, "mesh_force", win).max(axis=0) / w0,
        "transmission_error_ptp": np.ptp(_per_mesh(results, "transmission_error", win), axis=0),
        "force_ptp": np.ptp(fb, axis=0),
        "force_mean": fb.mean(axis=0),
        "orbit_centre": np.array(centres),
        "orbit_mean": journal.mean(axis=0),
    }


def run_report(results: dict, window: str | None = None) -> dict:
    """Figures of ``gsb run`` over the window of :func:`report_window` (the last revolution
    of the slowest shaft, or the last half of a shorter run, or the stored case's
    ``simulation.window``; ``window`` replaces it), for the train of the stored case
    (bearings and meshes in its order).

    Returns

    * ``dynamic_factor`` (n_meshes,): R of each mesh, its maximum force in the window over its
      static load (:func:`static_mesh_loads`);
    * ``transmission_error_ptp`` (n_meshes,) [m]: the peak-to-peak of each mesh's TE;
    * ``bearing_force_ptp`` (nb,): the peak-to-peak of ||F_b|| [N];
    * ``line_amplitudes`` (nb, n): the peak amplitudes [N] of the lines of ||F_b||
      (:func:`~orchestrator.analysis.spectrum.line_amplitudes`: least squares, NaN for a line
      the window does not resolve; the scale of the order spectrum of every figure) at every
      shaft's 1x and every mesh's first harmonics
      (:func:`~orchestrator.analysis.spectrum.train_lines`), named ``line_labels`` (n,), at
      ``line_frequencies`` (n,) [Hz], which
      are ``line_orders`` (nb, n) cycles per revolution of each bearing's own shaft;
    * ``mesh_names``, ``bearing_names``: the labels of those axes;
    * ``window_s`` (2,) [s]: the window's start and end (it holds the steps ending after the
      start) and ``window_kind``, its name; ``window_speeds`` (2,) [rad/s] the input speed
      there (a run-up's, ``drive.speed_profile``: the lines are at the speed of the window's
      end, and NaN when it varies over the window).
    """
    time_s = np.asarray(results["time"], dtype=float)
    if time_s.size < 2:
        raise ValueError(f"a report needs at least 2 time steps, got {time_s.size}")
    case = stored_case(results["attrs"], window=window)
    lay = layout(case)
    duration, kind = report_window(case, time_s)
    end_s = float(time_s[-1])
    win = steady_window(time_s, duration)
    force = np.asarray(results["bearing_force"], dtype=float)[win]
    norm = np.hypot(force[..., 0], force[..., 1])
    input_orders, labels = train_lines(lay)
    profile = speed_profile(case)
    speeds = (profile.speed(end_s - duration), profile.speed(end_s))
    input_hz = speeds[1] / (2.0 * np.pi)
    frequencies = input_orders * input_hz
    dt_s = (end_s - time_s[0]) / (time_s.size - 1)
    if speeds[0] == speeds[1]:
        amplitudes = line_amplitudes(time_s[win], norm, frequencies, duration, dt_s)
    else:  # a line of a varying speed is no line over the window
        amplitudes = np.full((frequencies.size, len(lay.bearings)), np.nan)
    ratios = np.array([float(lay.ratios[lay.shaft_index[b.shaft]]) for b in lay.bearings])
    return {
        "dynamic_factor": _per_mesh(results, "mesh_force", win).max(axis=0)
        / static_mesh_loads(case),
        "transmission_error_ptp": np.ptp(_per_mesh(results, "transmission_error", win), axis=0)
        if "transmission_error" in results else np.full(len(lay.meshes), np.nan),
        "bearing_force_ptp": np.ptp(norm, axis=0),
        "line_amplitudes": np.ascontiguousarray(amplitudes.T),
        "line_frequencies": frequencies,
        "line_orders": input_orders[None, :] / ratios[:, None],
        "line_labels": labels,
        "mesh_names": list(lay.mesh_names),
        "bearing_names": list(lay.bearing_names),
        "window_s": np.array([end_s - duration, end_s]),
        "window_kind": kind,
        "window_speeds": np.array(speeds),
    }
