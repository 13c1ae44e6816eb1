"""The Campbell diagram of ``gsb modal --campbell``: the damped modes of a case over input
speeds (:func:`orchestrator.analysis.campbell.campbell_data`) against the harmonics of every
mesh and every shaft's 1x line, with their crossings
(:func:`orchestrator.analysis.campbell.crossings`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from gear_fmu.modal.damped_modes import MESH_MODE_FRACTION
from orchestrator.analysis.campbell import HARMONICS, crossings
from orchestrator.figures.base import pyplot

__all__ = ["plot_campbell"]

#: marker of each whirl direction (gear_fmu.modal.whirl)
_WHIRL_MARKERS = {"forward": "^", "backward": "v", "mixed": "o", "none": "s"}


def plot_campbell(data: dict, path, title: str, harmonics: int = HARMONICS,
                  min_mesh_fraction: float = MESH_MODE_FRACTION) -> Path:
    """Campbell diagram PNG (module docstring): damped frequencies [Hz] against the input
    speed [rad/s] up to ``data["max_frequency"]``, coloured by damping ratio, marker shape by
    whirl direction (forward, backward, mixed, none), marker area by mesh energy share,
    unstable modes edged red with the stability threshold drawn; each mesh's harmonics (a
    colour per mesh) and each shaft's 1x line; crossings marked
    (:func:`orchestrator.analysis.campbell.crossings`)."""
    from matplotlib.colors import LogNorm

    plt = pyplot()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    w, lines, f_max = data["speeds"], data["lines"], data["max_frequency"]
    several = len(lines["meshes"]) > 1
    fig, ax = plt.subplots(figsize=(10, 7), constrained_layout=True)
    if w.size:
        x = np.linspace(0.0, w.max() * 1.05, 2)
        colours = ("tab:red", "tab:orange", "tab:purple", "tab:brown")
        for m, (mesh, order, z) in enumerate(zip(lines["meshes"], lines["mesh_orders"],
                                                 lines["teeth"], strict=True)):
            colour = colours[m % len(colours)]
            for k in range(1, harmonics + 1):
                label = None
                if k == 1:
                    label = (f"mesh {mesh}: f = k z r ω / 2π (z = {z}, r = {order / z:.4g})"
                             if several or order != z else "mesh orders f = k z1 ω / 2π")
                ax.plot(x, k * order * x / (2 * math.pi), "--", color=colour, lw=1.0,
                        alpha=0.8, label=label)
                at = min(0.95 * f_max, k * order * w.max() / (2 * math.pi))  # inside the axes
                ax.annotate(f"{mesh + ' ' if several else ''}k = {k}",
                            (at * 2 * math.pi / (k * order), at), textcoords="offset points",
                            xytext=(-3, 0), ha="right", va="center", color=colour, fontsize=9)
        order = sorted(zip(lines["shaft_ratios"], lines["shafts"], strict=True), reverse=True)
        for r, _ in order:
            ax.plot(x, r * x / (2 * math.pi), ":", color="k", lw=1.0)
        # one label on the steepest 1x line: the shafts' lines lie too close to name each
        top = order[0][0]
        ax.annotate("1× " + ", ".join(name for _, name in order)
                    + (" (steepest first)" if len(order) > 1 else ""),
                    (w.max(), top * w.max() / (2 * math.pi)), textcoords="offset points",
                    xytext=(-4, 4), ha="right", fontsize=9)
        ax.plot([], [], ":", color="k", lw=1.0,
                label="1× of each shaft" if len(order) > 1 else f"1× {order[0][1]}")
    for a, i, j in data["segments"]:
        ax.plot([w[a], w[a + 1]], [data["modes"][a]["frequency_hz"][i],
                                   data["modes"][a + 1]["frequency_hz"][j]],
                "-", color="0.6", lw=0.8, zorder=1)
    norm = LogNorm(vmin=0.01, vmax=1.0)
    sc = None
    for wi, m in zip(w, data["modes"], strict=True):
        share = np.nan_to_num(m["mesh_energy_fraction"], nan=0.0).clip(0.0, 1.0)
        zeta = m["damping_ratio"]
        for direction, marker in _WHIRL_MARKERS.items():
            on = m["whirl_direction"] == direction
            if not on.any():
                continue
            sc = ax.scatter(np.full(int(on.sum()), wi), m["frequency_hz"][on],
                            c=zeta[on].clip(0.01, 1.0), cmap="viridis_r", norm=norm,
                            marker=marker, s=(16 + 110 * share[on]),
                            edgecolors=np.where(zeta[on] < 0.0, "tab:red", "k"),
                            linewidths=np.where(zeta[on] < 0.0, 1.8, 0.3), zorder=3)
    if sc is not None:
        fig.colorbar(sc, ax=ax, label="damping ratio ζ [-] (ζ ≤ 0.01 and unstable ζ < 0 "
                                      "at the light end)")
    threshold = data.get("stability_threshold")
    if threshold is not None:
        ax.axvline(threshold, color="tab:red", lw=1.5,
                   label=f"stability threshold {threshold:.0f} rad/s: a mode's ζ < 0 "
                         "beyond (red edges)")
    cross = crossings(data, harmonics, min_mesh_fraction)
    mesh = [c for c in cross if c["harmonic"] > 0 and c["frequency_hz"] <= f_max]
    once = [c for c in cross if c["harmonic"] == 0 and c["frequency_hz"] <= f_max]
    if mesh:
        ax.plot([c["speed_rad_s"] for c in mesh], [c["frequency_hz"] for c in mesh], "x",
                color="tab:red", ms=11, mew=2.2, zorder=4,
                label=f"mesh harmonic × mode with ≥ {min_mesh_fraction:.0%} of its strain "
                      "energy in that mesh (ω in rad/s)")
        for c in mesh:
            ax.annotate(f"{c['speed_rad_s']:.0f}", (c["speed_rad_s"], c["frequency_hz"]),
                        textcoords="offset points", xytext=(0, 9), ha="center",
                        va="bottom", rotation=90, color="tab:red", fontsize=8)
    if once:
        ax.plot([c["speed_rad_s"] for c in once], [c["frequency_hz"] for c in once], "o",
                mfc="none", mec="k", ms=8, zorder=4, label="1× line × mode")
    ax.set_xlim(0.0, (w.max() if w.size else 1.0) * 1.05)
    ax.set_ylim(0.0, f_max)
    ax.set_xlabel("input speed ω [rad/s]")
    ax.set_ylabel("damped natural frequency f_d [Hz]")
    rpm = ax.secondary_xaxis("top", functions=(lambda v: v * 30 / math.pi,
                                               lambda v: v * math.pi / 30))
    rpm.set_xlabel("input speed [rpm]")
    ax.grid(True, alpha=0.3)
    ax.set_title(title, fontsize=11)
    handles, labels = ax.get_legend_handles_labels()
    for direction, marker in _WHIRL_MARKERS.items():
        handles.append(plt.Line2D([], [], ls="none", marker=marker, mfc="0.7", mec="k", ms=9))
        labels.append({"none": "axial or torsional (no whirl)"}.get(direction,
                                                                     f"{direction} whirl")
                      + (" (marker area: mesh strain energy share)"
                         if direction == "forward" else ""))
    fig.legend(handles, labels, loc="outside lower center", ncols=2, fontsize=9)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
