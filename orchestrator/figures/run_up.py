"""``run_up.png``: the figure of a run whose input speed changes (``drive.speed_profile``),
drawn by :func:`orchestrator.figures.run.run_figures` beside the others.

Top, the input speed against time. Then a row per shaft, for the first bearing on it, in orders
of that shaft (cycles per revolution): left, the amplitude of ||F_b|| at each line of the
train (every shaft's 1x, each mesh's first harmonics) tracked against the input speed
(:func:`orchestrator.analysis.order_tracking.tracked_orders`, windows of two revolutions of the
shaft, a line the window cannot separate left out), with the critical speeds of the Campbell
diagram over the run's speeds drawn where a mode crosses a line
(:func:`orchestrator.analysis.campbell.crossings`); right, the order-tracked waterfall
(:func:`orchestrator.analysis.order_tracking.order_waterfall`), speed against order, the peak
amplitude in colour (log scale).
"""

from __future__ import annotations

import numpy as np

from orchestrator.analysis.spectrum import HARMONICS
from orchestrator.figures.base import AMPLITUDE_LABEL, RunData, titled_figure

__all__ = ["draw_run_up", "run_up_lines"]

#: revolutions of a bearing's shaft in each tracking window (its own 1x needs 1.5)
WINDOW_REVOLUTIONS = 2.0


def run_up_lines(run: RunData) -> tuple[list[float], list[str]]:
    """The train's lines in orders of the input shaft and their names: every shaft's 1x, the
    first :data:`~orchestrator.analysis.spectrum.HARMONICS` harmonics of each mesh (those
    the Campbell diagram's crossings name)."""
    orders, names = [], []
    for shaft, ratio in run.ratios.items():
        orders.append(ratio)
        names.append(f"{shaft} 1x")
    for mesh, order in zip(run.meshes, run.mesh_orders, strict=True):
        for k in range(1, HARMONICS + 1):
            orders.append(k * order)
            names.append(f"{mesh} {'' if k == 1 else k}GMF")
    return orders, names


def _critical_speeds(run: RunData, speeds) -> tuple[list[dict], str]:
    """The Campbell diagram's crossings within the run's speeds (six speeds across them), or
    none and why."""
    from orchestrator.analysis.campbell import campbell_data, crossings

    lo, hi = float(np.min(speeds)), float(np.max(speeds))
    try:
        data = campbell_data(run.case, np.linspace(lo, hi, 6))
        return [c for c in crossings(data) if lo <= c["speed_rad_s"] <= hi], ""
    except Exception as exc:  # the figure without them, saying why
        return [], f"critical speeds not computed: {type(exc).__name__}: {exc}"


def draw_run_up(plt, run: RunData) -> object:
    """The figure (module docstring) of a run-up's results (the speeds and angles from the
    stored case's ``drive.speed_profile``)."""
    from matplotlib.colors import LogNorm

    from fmu_src.description import speed_profile
    from orchestrator.analysis.campbell import line_name
    from orchestrator.analysis.order_tracking import order_waterfall, tracked_orders

    profile = speed_profile(run.case)
    input_speed = np.array([profile.speed(t) for t in run.time])
    input_rev = np.array([profile.angle(t) for t in run.time]) / (2.0 * np.pi)
    orders, names = run_up_lines(run)
    crit, why = _critical_speeds(run, input_speed)
    rows = [(s, run.bearing_shaft.index(s)) for s in run.shafts if s in run.bearing_shaft]
    fig = titled_figure(plt, run, f"run-up {profile.omega0:g} -> {profile.omega1:g} rad/s: "
                                  f"||F_b|| order-tracked", figsize=(13.0, 2.2 + 3.2 * len(rows)))
    grid = fig.add_gridspec(1 + len(rows), 2, height_ratios=[0.6] + [1.0] * len(rows))
    ax = fig.add_subplot(grid[0, :])
    ax.plot(run.time, input_speed, color="k")
    ax.set(xlabel="time [s]", ylabel="input speed [rad/s]",
           title=f"input shaft {run.input_shaft}: drive.speed_profile = "
                 f"'{run.case['drive.speed_profile']}'")
    ax.grid(alpha=0.3)
    for row, (shaft, b) in enumerate(rows, start=1):
        ratio = run.ratios[shaft]
        revs = input_rev * ratio
        own = [q / ratio for q in orders]
        tracked = tracked_orders(revs, input_speed, run.force_norm[:, b], own,
                                 WINDOW_REVOLUTIONS, WINDOW_REVOLUTIONS / 4)
        ax = fig.add_subplot(grid[row, 0])
        if not tracked["speed"].size:
            ax.text(0.5, 0.5, f"the run holds {revs[-1] - revs[0]:.3g} revolutions of {shaft}, "
                              f"fewer than a window's {WINDOW_REVOLUTIONS:g}: nothing tracked",
                    transform=ax.transAxes, ha="center", va="center", fontsize=9)
            ax.set(title=f"bearing {run.bearings[b]} ({shaft})", xticks=[], yticks=[])
            continue
        for k, name in enumerate(names):
            amp = tracked["amplitudes"][:, k]
            if np.isfinite(amp).any():
                ax.semilogy(tracked["speed"], amp, label=f"{name} (order {own[k]:.4g})")
        for c in crit:
            ax.axvline(c["speed_rad_s"], color="0.5", ls=":", lw=0.8)
            ax.annotate(line_name(c), (c["speed_rad_s"], 1.0), xycoords=("data", "axes fraction"),
                        rotation=90, va="top", ha="right", fontsize=7, color="0.35")
        ax.set(xlabel="input speed [rad/s]", ylabel=AMPLITUDE_LABEL,
               title=f"bearing {run.bearings[b]} ({shaft}): lines tracked over "
                     f"{WINDOW_REVOLUTIONS:g} revolutions of {shaft}")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7, loc="lower right")
        per_revolution = 2 * int(np.ceil(revs.size / (revs[-1] - revs[0])))  # the samples'
        fall = order_waterfall(revs, input_speed, run.force_norm[:, b], WINDOW_REVOLUTIONS,
                               WINDOW_REVOLUTIONS / 4, per_revolution,
                               max_order=1.2 * max(own))
        ax = fig.add_subplot(grid[row, 1])
        if fall["amplitudes"].size:
            amp = fall["amplitudes"][:, 1:]  # order 0, the mean, left out
            floor = max(np.nanmax(amp) * 1e-3, 1e-12)
            mesh = ax.pcolormesh(fall["orders"][1:], fall["speed"], np.maximum(amp, floor),
                                 norm=LogNorm(floor, np.nanmax(amp)),
                                 shading="nearest", cmap="viridis")
            fig.colorbar(mesh, ax=ax, label=AMPLITUDE_LABEL)
        ax.set(xlabel=f"order [1/{shaft} rev]", ylabel="input speed [rad/s]",
               title=f"bearing {run.bearings[b]}: waterfall")
    if why:
        fig.text(0.01, 0.005, why, fontsize=7, color="tab:red", va="bottom")
    return fig
