"""Figures of a run: ``gsb run`` draws them at its end, ``gsb plot FILE`` from any results file
(also an incomplete one, or one still being written), for any gear train: the bearings,
shafts and meshes are those of the case stored in the file, by their names.

:func:`run_figures` writes four PNGs into the folder beside the results file
(``<file stem>/``), each titled with the case, bearing model, mode, input speed, torque and
unbalance (:func:`orchestrator.figures.base.run_title`):

``orbits.png``
    the journal-centre orbit of every bearing [µm], a row per shaft, each panel titled by the
    bearing's name and shaft, zoomed on the orbit, the report's window (the last revolution
    of the slowest shaft) drawn over the whole (faded) trajectory, the static position X0
    marked, and an inset with the bearing's full clearance circle;
``bearing_forces.png``
    ||F_b|| of every bearing over the last revolution of the input shaft, a panel per shaft;
``spectra.png``
    order spectra of ||F_b|| over the report's window in peak amplitude, a panel per shaft
    in orders of that shaft (:func:`orchestrator.analysis.spectrum.order_spectrum`,
    :func:`run_spectrum`), with every shaft's 1x and every mesh's harmonics marked, and their
    least-squares amplitudes on the same scale (those of the report of ``gsb run``) drawn
    and listed;
``mesh.png``
    per mesh, its transmission error and dynamic mesh force over the last input revolution
    and over the whole run (max / min / mean per input revolution: :func:`envelope`). The TE
    is drawn about its mean over the report's window, the mean stated: it holds the static
    deflection under the torque, the shafts' torsional wind-up included, which the dynamic
    reading of TE (peak-to-peak, orders) leaves out;
``run_up.png``
    of a run-up only (``drive.speed_profile``): the lines of ||F_b|| tracked against the speed
    and the order waterfall (:mod:`orchestrator.figures.run_up`).

Channels read (:func:`orchestrator.run.channels.channels`): ``time`` [s],
``journal_position`` (nb, 2) [m], ``bearing_force`` (nb, 2) [N], ``mesh_force``
(n_meshes,) [N], ``transmission_error`` (n_meshes,) [m]; root attributes ``case_toml`` (the
train), ``case``, ``bearing_model``, ``mode``, ``speed`` [rad/s], ``torque`` [N m],
``unbalance`` [m], ``static_journal`` (nb, 2) [m], ``static_mesh_force`` [N],
``static_transmission_error`` [m], ``complete``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.ticker import FormatStrFormatter, MaxNLocator

from fmu_src.description import speed_profile
from orchestrator.analysis.spectrum import (
    HARMONICS,
    PAD,
    line_amplitudes,
    order_spectrum,
    spectral_resolution,
    train_lines,
)
from orchestrator.figures.base import (
    AMPLITUDE_LABEL,
    DPI,
    UM,
    RunData,
    bearing_style,
    num_attr,
    order_label,
    pyplot,
    titled_figure,
)
from orchestrator.figures.run_up import draw_run_up
from orchestrator.run.results import read_results

__all__ = ["RUN_FIGURES", "envelope", "make_run_figures", "run_figures", "run_spectrum"]

#: the PNGs :func:`run_figures` writes (and removes first when stale)
RUN_FIGURES = ("orbits.png", "bearing_forces.png", "spectra.png", "mesh.png")
#: names of earlier versions, and the run-up's figure (:mod:`orchestrator.figures.run_up`),
#: removed as stale too
_OLD_FIGURES = ("bearing_force.png", "mesh_force.png", "run_up.png")


def _corners(sw: float, sh: float, pad: float):
    """Axes-fraction bounds ``[left, bottom, sw, sh]`` of the four corner boxes, upper right
    first."""
    for cu, cv in ((1, 1), (0, 1), (1, 0), (0, 0)):
        yield [1 - pad - sw if cu else pad, 1 - pad - sh if cv else pad, sw, sh]


def _zoom(xs, ys, shape: float, floor: float = 1e-3, side: float = 0.34, margin: float = 0.1,
          pad: float = 0.015):
    """Limits of an equal-aspect zoom on the points ``xs, ys`` (extent at least ``floor``) in
    an axes of height / width ``shape``, leaving a corner box free for an inset (of side
    ``side`` times the smaller axes dimension): ``(xlim, ylim, inset bounds in axes
    fraction)``.

    The points are centred with ``margin`` of their extent on each side if a corner is then
    free of them; otherwise they are moved to the left (or the bottom) of the axes and the
    inset goes into the strip left free, whichever zooms more."""
    xs, ys = np.asarray(xs, dtype=float), np.asarray(ys, dtype=float)
    x0, x1, y0, y1 = xs.min(), xs.max(), ys.min(), ys.max()
    floor = max(floor, 0.1 * max(x1 - x0, y1 - y0))
    w, h = max(x1 - x0, floor), max(y1 - y0, floor)
    sw, sh = side * min(1.0, shape), side * min(1.0, 1.0 / shape)  # a square inset
    cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)

    def fit(hx, hy):  # half ranges with the axes' shape (equal aspect)
        return (hx, hx * shape) if hy < hx * shape else (hy / shape, hy)

    hx, hy = fit(w * (0.5 + margin), h * (0.5 + margin))
    xlim, ylim = (cx - hx, cx + hx), (cy - hy, cy + hy)
    u, v = (xs - xlim[0]) / (2 * hx), (ys - ylim[0]) / (2 * hy)
    for box in _corners(sw, sh, pad):
        if not np.any((u > box[0] - pad) & (u < box[0] + sw + pad)
                      & (v > box[1] - pad) & (v < box[1] + sh + pad)):
            return xlim, ylim, box
    # the points in the left part, the inset in the right strip; or bottom and top
    right = fit(w * (1 + 2 * margin) / (2 * (1 - sw - 2 * pad)), h * (0.5 + margin))
    top = fit(w * (0.5 + margin), h * (1 + 2 * margin) / (2 * (1 - sh - 2 * pad)))
    if right[0] <= top[0]:
        hx, hy = right
        left = x0 - margin * w
        return (left, left + 2 * hx), (cy - hy, cy + hy), [1 - pad - sw, 1 - pad - sh, sw, sh]
    hx, hy = top
    bottom = y0 - margin * h
    return (cx - hx, cx + hx), (bottom, bottom + 2 * hy), [1 - pad - sw, 1 - pad - sh, sw, sh]


def _orbits(plt, run: RunData):
    from matplotlib.lines import Line2D
    from matplotlib.patches import Rectangle

    groups = [(shaft, on) for shaft, on in run.groups() if on]
    ncols = max(len(on) for _, on in groups)
    nrows = len(groups)
    width = max(7.0, 4.2 * ncols + 1.8)
    fig = titled_figure(plt, run, "journal-centre orbits",
                        figsize=(width, 3.4 * nrows + 1.9))
    grid = fig.subplots(nrows, ncols, squeeze=False)
    win, kind, _ = run.long_window()
    span_ms = (run.time[win][-1] - run.time[win][0] + run.dt) * 1e3
    circle = np.linspace(0.0, 2.0 * np.pi, 361)
    insets = []
    for row, (shaft, on) in zip(grid, groups, strict=True):
        for ax in row[len(on):]:
            ax.set_visible(False)
        for ax, b in zip(row, on, strict=False):
            colour = bearing_style(b)[0]
            s, t = run.journal[:, b, 0] * UM, run.journal[:, b, 1] * UM
            ax.plot(s, t, color="0.6", lw=0.5, alpha=0.6, zorder=1)
            ax.plot(s[win], t[win], color=colour, lw=1.3, zorder=3)
            ax.plot(s[-1], t[-1], "o", color=colour, ms=4, zorder=4)
            xs, ys = list(s[win]), list(t[win])
            x0 = None if run.static_journal is None else run.static_journal[b] * UM
            if x0 is not None:
                ax.plot(*x0, "P", color="k", ms=9, mec="w", mew=0.8, zorder=5)
                xs.append(x0[0])
                ys.append(x0[1])
            c = float(run.clearance[b]) * UM
            ax.ticklabel_format(useOffset=False)
            # at most 5 ticks: values such as 39.925 overlap at the default count
            ax.xaxis.set_major_locator(MaxNLocator(nbins=5))
            ax.grid(True, lw=0.4, alpha=0.5)
            ax.set_xlabel("s [µm]")
            ax.set_ylabel("t [µm]")
            title = f"bearing {run.bearings[b]} (shaft {shaft})"
            if x0 is not None and c:
                title += f", X0 at e/C = {math.hypot(*x0) / c:.2f}"
            ax.set_title(title, fontsize=11)
            insets.append((ax, xs, ys, c, s, t, colour))
    handles = [Line2D([], [], color="0.6", lw=1, label="whole run (transient from X0)"),
               Line2D([], [], color="C0", lw=1.5,
                      label=f"{kind} ({span_ms:.1f} ms; colour per bearing)"),
               Line2D([], [], color="C0", marker="o", ls="", ms=4, label="last step"),
               Line2D([], [], color="k", marker="P", ls="", ms=8, label="static position X0"),
               Rectangle((0, 0), 1, 1, fill=False, ec="r",
                         label="inset: clearance circle, red box = zoomed region")]
    # two columns: three ran wider than the figure
    fig.legend(handles=handles, loc="outside lower center", ncol=2, fontsize=9, frameon=False)
    fig.draw_without_rendering()  # the layout: the panels' shape sets the zoom limits
    for ax, xs, ys, c, s, t, colour in insets:  # zoom on the steady orbit and X0
        box = ax.get_position()
        shape = (box.height * fig.get_figheight()) / (box.width * fig.get_figwidth())
        xlim, ylim, bounds = _zoom(xs, ys, shape, floor=1e-4 * (c or 1.0))
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
        ax.set_aspect("equal", adjustable="box")
        if c:
            ins = ax.inset_axes(bounds)
            ins.set_anchor("NE")
            ins.plot(c * np.cos(circle), c * np.sin(circle), "k-", lw=0.8)
            ins.plot(s, t, color=colour, lw=0.6)
            (u0, u1), (v0, v1) = xlim, ylim
            if max(u1 - u0, v1 - v0) > 0.15 * c:
                ins.add_patch(Rectangle((u0, v0), u1 - u0, v1 - v0, fill=False, ec="r",
                                        lw=0.9))
            else:  # too small to see: a red square marker around it
                ins.plot(0.5 * (u0 + u1), 0.5 * (v0 + v1), "s", mfc="none", mec="r", ms=7,
                         mew=1.0)
            ins.set_xlim(-1.08 * c, 1.08 * c)
            ins.set_ylim(-1.08 * c, 1.08 * c)
            ins.set_aspect("equal")
            ins.set_xticks([])
            ins.set_yticks([])
            ins.patch.set_alpha(0.92)
            ins.text(0.5, 0.03, f"C = {c:.0f} µm", transform=ins.transAxes, ha="center",
                     va="bottom", fontsize=7)
    return fig


def _angle_axis(ax, run: RunData, t_start: float):
    """Top axis in ms of run time for a bottom axis in degrees of the input shaft since
    ``t_start``."""
    deg_per_s = math.degrees(run.speed)
    top = ax.secondary_xaxis("top", functions=(lambda a: (t_start + a / deg_per_s) * 1e3,
                                               lambda ms: (ms * 1e-3 - t_start) * deg_per_s))
    top.set_xlabel("time [ms]")
    # at most 5 labels: run times of four or five digits stay apart over a panel's width
    top.xaxis.set_major_locator(MaxNLocator(nbins=4, steps=[1, 2, 5, 10]))
    top.xaxis.set_major_formatter(FormatStrFormatter("%g"))
    return top


def _bearing_forces(plt, run: RunData):
    groups = [(shaft, on) for shaft, on in run.groups() if on]
    fig = titled_figure(plt, run, "bearing force norms ||F_b||",
                        figsize=(11, 2.6 * len(groups) + 2.4))
    axes = fig.subplots(len(groups), 1, sharex=True, squeeze=False)[:, 0]
    win, kind = run.short_window()
    t = run.time[win]
    t_start = t[0] - run.dt
    angle = (t - t_start) * math.degrees(run.speed)
    every = max(1, t.size // 28)
    for ax, (shaft, on) in zip(axes, groups, strict=True):
        for j, b in enumerate(on):
            colour, ls, marker = bearing_style(b)
            force = run.force_norm[win, b]
            label = f"bearing {run.bearings[b]}"
            for other in on[:j]:  # a curve drawn over an equal one: say so, it hides it
                gap = float(np.abs(force - run.force_norm[win, other]).max())
                if gap <= 1e-3 * float(np.abs(force).max()):
                    label += f"\n(on bearing {run.bearings[other]}: within {gap:.2g} N)"
                    break
            ax.plot(angle, force, color=colour, ls=ls, marker=marker,
                    lw=2.0 if j % 2 == 0 else 1.4, ms=6, mfc=colour if j % 2 == 0 else "none",
                    markevery=(j * every // max(len(on), 1), every), label=label,
                    zorder=2 + j)
        ax.set_ylabel("||F_b|| [N]")
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.grid(True, lw=0.4, alpha=0.5)
        ax.legend(loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=9, frameon=False,
                  title=f"shaft {shaft}", title_fontsize=9)  # beside the panel: none hidden
    axes[-1].set_xlabel(f"angle of the input shaft {run.input_shaft} [deg] ({kind})")
    axes[-1].set_xlim(angle[0], angle[-1])
    if angle[-1] > 300:
        axes[-1].set_xticks(np.arange(0, 361, 45))
    _angle_axis(axes[0], run, t_start)
    return fig


def run_spectrum(run: RunData) -> dict:
    """What ``spectra.png`` draws: the order spectrum of ||F_b|| of every bearing over the
    report's window (the last revolution of the slowest shaft, the last half of a shorter
    run) in orders of its own shaft (:func:`~orchestrator.analysis.spectrum.order_spectrum`
    with that shaft's rotation frequency): ``orders`` (nb, m) [1/rev of bearing b's shaft]
    and ``amplitudes`` (m, nb) [N]; the least-squares peak amplitudes ``lines`` (nb, n) [N]
    of the train's lines (:func:`~orchestrator.analysis.spectrum.train_lines`) named
    ``line_labels``, at ``line_orders`` (nb, n) of each bearing's shaft, over the same
    window, as the report of ``gsb run`` computes them; ``window`` the mask, ``kind`` its
    name, ``duration`` [s] and ``resolution`` (nb,) [orders of each bearing's shaft]."""
    win, kind, duration = run.long_window()
    n = int(win.sum())
    nb = len(run.bearings)
    amplitudes = None
    orders = []
    for b in range(nb):  # one spectrum per bearing, in orders of its shaft
        q, amp = order_spectrum(run.force_norm[win, b], run.dt,
                                run.shaft_hz(run.bearing_shaft[b]))
        if amplitudes is None:
            amplitudes = np.empty((amp.size, nb))
        amplitudes[:, b] = amp
        orders.append(q)
    input_orders, labels = train_lines(run.layout)
    dt_s = (run.time[-1] - run.time[0]) / (run.steps - 1)  # as the report's
    lines = line_amplitudes(run.time[win], run.force_norm[win], input_orders * run.input_hz,
                            duration, dt_s)
    ratios = np.array([run.ratios[s] for s in run.bearing_shaft])
    return {"orders": np.array(orders), "amplitudes": amplitudes, "window": win, "kind": kind,
            "duration": duration,
            "resolution": np.array([spectral_resolution(n, run.dt, run.shaft_hz(s))
                                    for s in run.bearing_shaft]),
            "lines": lines.T, "line_orders": input_orders[None, :] / ratios[:, None],
            "line_labels": labels}


def _short(value: float) -> str:
    """At most 6 characters: 3 significant digits, '-' for NaN."""
    if not np.isfinite(value):
        return "-"
    text = f"{value:.3g}"
    if len(text) <= 6:
        return text
    return f"{value:.0f}" if 1e3 <= abs(value) < 1e6 else f"{value:.0e}"


def _spectra(plt, run: RunData):
    spec = run_spectrum(run)
    groups = [(shaft, on) for shaft, on in run.groups() if on]
    names = run.bearings
    cell = max(7, *(len(n) + 1 for n in names))
    labels = spec["line_labels"]
    label_width = max(len(x) for x in labels) + 1
    table_chars = label_width + cell * len(names)
    side_in = max(2.6, 0.075 * table_chars + 0.3)  # monospace 8.5 pt: ~0.075 in a character
    fig = titled_figure(plt, run, "order spectra of ||F_b||",
                        figsize=(8.4 + side_in, max(8.0, 3.0 * len(groups) + 2.2)))
    grid = fig.add_gridspec(len(groups), 2, width_ratios=[8.4, side_in])
    axes = [fig.add_subplot(grid[0, 0])]
    axes += [fig.add_subplot(grid[k, 0]) for k in range(1, len(groups))]
    amp, lines = spec["amplitudes"], spec["lines"]
    win, kind = spec["window"], spec["kind"]
    top = 1e-12
    ranges = []
    for shaft, on in groups:
        b0 = on[0]
        q, orders, resolution = spec["orders"][b0], spec["line_orders"][b0], \
            spec["resolution"][b0]
        highest = max([1.0] + [HARMONICS * m / run.ratios[shaft] for m in run.mesh_orders])
        q_lo = max(0.6 * min(orders.min(), 1.0), 0.5 * resolution)
        q_hi = min(1.2 * highest, q[-1])
        keep = (q >= q_lo * 0.9) & (q <= q_hi)
        if keep.any():
            top = max(top, float(amp[keep][:, on].max()))
        ranges.append((q, orders, q_lo, q_hi, keep))
    shaded = False
    for ax, (shaft, on), (q, orders, q_lo, q_hi, keep) in zip(axes, groups, ranges,
                                                               strict=True):
        # the Hann main lobe about order 0 (2 resolutions): a line there overlaps its
        # negative-frequency image and the removed mean, and the curve is not its amplitude
        lobe = 2.0 * spec["resolution"][on[0]]
        if lobe > q_lo:
            ax.axvspan(q_lo, min(lobe, q_hi), color="0.9", zorder=0,
                       label=None if shaded else "within 2 resolutions of order 0 (Hann main "
                                                 "lobe):\nthe curve is not the line there; "
                                                 "its marker is")
            shaded = True
        for j, b in enumerate(on):
            colour, ls, marker = bearing_style(b)
            ax.plot(q[keep], amp[keep, b], color=colour, ls=ls, lw=1.5 if j % 2 == 0 else 1.1,
                    label=f"bearing {names[b]} (spectrum)", zorder=2 + j)
            shown = (orders >= q_lo) & (orders <= q_hi)
            ax.plot(orders[shown], lines[b][shown], ls="", marker=marker, color=colour, ms=8,
                    mfc=colour if j % 2 == 0 else "none", mew=1.5, zorder=5,
                    label=f"bearing {names[b]} (least-squares line)")
        for order, label in zip(orders, labels, strict=True):
            if q_lo <= order <= q_hi:
                ax.axvline(order, color="0.45", ls=":", lw=0.9, zorder=1)
                ax.text(order, 1.0, " " + label, rotation=90, ha="right", va="top",
                        fontsize=8, color="0.3", transform=ax.get_xaxis_transform())
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylim(top * 1e-5, top * 3.0)
        ax.set_xlim(q_lo, q_hi)
        ax.grid(True, which="major", lw=0.4, alpha=0.5)
        ax.set_ylabel(AMPLITUDE_LABEL)
        ax.set_title(f"shaft {shaft}", fontsize=11, loc="left")
        ticks = sorted({*np.round(orders[(orders >= q_lo) & (orders <= q_hi)], 9),
                        *[v for v in (0.5, 2, 5, 10) if q_lo <= v <= q_hi]})
        ax.set_xticks(ticks, [f"{v:.3g}" for v in ticks], fontsize=8)
        ax.set_xticks([], minor=True)
        ax.set_xlabel(f"{order_label(shaft)} (f / {run.shaft_hz(shaft):.4g} Hz)")
    # the table of least-squares amplitudes beside the panels
    text = [f"{kind}", f"{spec['duration'] * 1e3:.1f} ms, {win.sum()} steps", "",
            "least-squares peak amplitudes [N]", ""]
    text.append(f"{'line':<{label_width}}" + "".join(f"{n:>{cell}}" for n in names))
    for k, label in enumerate(labels):
        text.append(f"{label:<{label_width}}"
                    + "".join(f"{_short(v):>{cell}}" for v in lines[:, k]))
    text += ["", "- : not resolved by the window", "",
             "spectrum: peak amplitude,", f"Hann window, zero-padded x{PAD}",
             "(docs/equations.md)"]
    side = fig.add_subplot(grid[:, 1])
    side.axis("off")
    side.text(0.0, 1.0, "\n".join(text), family="monospace", fontsize=8.5, va="top",
              transform=side.transAxes)
    handles = [h for ax in axes for h in ax.get_legend_handles_labels()[0]]
    side.legend(handles=handles, loc="lower left", fontsize=8.5, frameon=False,
                borderaxespad=0.0)
    return fig


#: the whole-run panels of ``mesh.png`` bin by input revolution from this many revolutions on
#: (fewer: by the mesh's period)
MIN_REVOLUTIONS = 10


def envelope(time, y, span: float) -> dict:
    """Max, min and mean of ``y`` per bin of ``span`` seconds of run time, the last bin ending
    at the last sample (a partial first bin kept if at least half a span, else merged into
    the next): ``centre`` [s], ``hi``, ``lo``, ``mean`` per bin.

    A bin of one input revolution holds every period of the meshes on the input shaft and
    every order of that shaft whole, so its max and min do not beat with them (bins of a few
    mesh periods alias against the revolution: a moire on a long run)."""
    time, y = np.asarray(time, dtype=float), np.asarray(y, dtype=float)
    n_bins = max(1, math.floor((time[-1] - time[0]) / span + 1e-9))
    # a bin holds the samples after its left edge; half a step off the samples: a whole
    # number of steps per span gives that number per bin, whatever the rounding of the times
    half_step = 0.5 * float(np.median(np.diff(time))) if time.size > 1 else 0.0
    edges = time[-1] - span * np.arange(n_bins, 0, -1) + half_step
    starts = np.searchsorted(time, edges, side="right")
    if starts[0] >= 1 and time[starts[0] - 1] - time[0] >= 0.5 * span:
        starts = np.r_[0, starts]  # the partial first bin kept
    else:
        starts[0] = 0  # merged into the first whole bin
    starts = np.unique(starts)
    ends = np.r_[starts[1:], time.size]
    return {"centre": 0.5 * (time[starts] + time[ends - 1]),
            "hi": np.maximum.reduceat(y, starts), "lo": np.minimum.reduceat(y, starts),
            "mean": np.add.reduceat(y, starts) / (ends - starts)}


def _whole_run(ax, run: RunData, y, colour, mesh: int) -> str:
    """``y`` over the whole run as its envelope per input revolution (per period of mesh
    ``mesh`` on a run of fewer than :data:`MIN_REVOLUTIONS` revolutions; the line itself
    under 1200 samples); returns the legend label of the envelope ("" for the line)."""
    if y.size <= 1200:
        ax.plot(run.time * 1e3, y, color=colour, lw=0.7)
        return ""
    revolutions = (run.time[-1] - run.time[0]) / run.input_rev
    if revolutions >= MIN_REVOLUTIONS:
        span, what = run.input_rev, "input revolution"
    else:
        span, what = run.input_rev / run.mesh_orders[mesh], "mesh period"
    env = envelope(run.time, y, span)
    x = env["centre"] * 1e3
    label = f"max / min per {what} ({span * 1e3:.3g} ms)"
    ax.fill_between(x, env["lo"], env["hi"], color=colour, alpha=0.25, lw=0)
    ax.plot(x, env["hi"], color=colour, lw=1.0, label=label)
    ax.plot(x, env["lo"], color=colour, lw=1.0)
    ax.plot(x, env["mean"], color="0.3", lw=0.7, label=f"mean per {what}")
    return label


def _mesh(plt, run: RunData):
    n = len(run.meshes)
    fig = titled_figure(plt, run, "dynamic transmission error and mesh force"
                        + (" of each mesh" if n > 1 else ""),
                        figsize=(11, 3.3 * 2 * n + 1.6) if n > 1 else (11, 8))
    axes = fig.subplots(2 * n, 2, sharex="col", width_ratios=[1, 1.25], squeeze=False)
    win, kind = run.short_window()
    t = run.time[win]
    t_start = t[0] - run.dt
    angle = (t - t_start) * math.degrees(run.speed)
    steady, steady_kind, _ = run.long_window()
    captions = []
    for m, name in enumerate(run.meshes):
        te_axes, force_axes = axes[2 * m], axes[2 * m + 1]
        which = f" ({name})" if n > 1 else ""
        w0 = None if run.static_mesh is None else float(run.static_mesh[m])
        dyn = run.mesh[:, m] - (w0 if w0 is not None else 0.0)
        dyn_label = f"W - W0{which} [N]" if w0 is not None else f"mesh force W{which} [N]"
        if run.te is not None:
            # the dynamic part about the steady mean: the mean holds the static deflection
            # under the torque, most of it the shafts' torsional wind-up, which the NVH
            # reading of TE (its peak-to-peak, its orders) leaves out
            te = run.te[:, m]
            mean = float(te[steady].mean())
            te_dyn = (te - mean) * UM
            te_axes[0].plot(angle, te_dyn[win], color="C4", lw=1.0)
            te_axes[0].axhline(0.0, color="k", ls=":", lw=0.9)
            if run.static_te is not None:
                static = float(run.static_te[m])
                te_axes[0].axhline((static - mean) * UM, color="0.4", ls="--", lw=0.9,
                                   label=f"static TE at X0: {static * UM:.4g} µm "
                                         f"({(static - mean) * UM:+.3g} µm from the mean)")
                te_axes[0].legend(loc="best", fontsize=9)
            for ax in te_axes:
                ax.set_ylabel(f"TE - mean{which} [µm]")
            _whole_run(te_axes[1], run, te_dyn, "C4", m)
            te_axes[1].axhline(0.0, color="k", ls=":", lw=0.9)
            te_axes[0].set_title(f"{'mesh ' + name + ': ' if n > 1 else ''}TE peak-to-peak "
                                 f"{np.ptp(te_dyn[win]):.3g} µm", fontsize=11)
            captions.append(f"{'mesh ' + name + ': ' if n > 1 else ''}drawn about its mean "
                            f"{mean * UM:.1f} µm over the {steady_kind}")
        else:
            for ax in te_axes:
                ax.text(0.5, 0.5, "no transmission_error channel", ha="center",
                        transform=ax.transAxes)
            te_axes[0].set_title(kind, fontsize=11)
        force_axes[0].plot(angle, dyn[win], color="C5", lw=1.0)
        force_axes[0].axhline(0.0, color="k", ls=":", lw=0.9)
        force_axes[0].set_ylabel(dyn_label)
        _whole_run(force_axes[1], run, dyn, "C5", m)
        force_axes[1].axhline(0.0, color="k", ls=":", lw=0.9)
        force_axes[1].set_ylabel(dyn_label)
        if w0:
            for ax in force_axes:
                ratio = ax.secondary_yaxis("right", functions=(
                    lambda f, w0=w0: 1.0 + f / w0, lambda r, w0=w0: (r - 1.0) * w0))
                ratio.set_ylabel("W / W0")
        te_axes[1].set_title(f"{'mesh ' + name + ', ' if n > 1 else ''}whole run",
                             fontsize=11)
    axes[-1, 0].set_xlabel(f"angle of the input shaft {run.input_shaft} [deg]\n({kind})")
    axes[-1, 0].set_xlim(angle[0], angle[-1])
    if angle[-1] > 300:
        axes[-1, 0].set_xticks(np.arange(0, 361, 60))
    _angle_axis(axes[0, 0], run, t_start)
    axes[-1, 1].set_xlabel("time [ms]")
    for ax in axes[:, 1]:
        if not win.all():
            ax.axvspan(t[0] * 1e3, t[-1] * 1e3, color="0.85", zorder=0,
                       label="left panels' window")
        ax.set_xlim(0.0, run.time[-1] * 1e3)
    handles, labels = axes[-1, 1].get_legend_handles_labels()
    caption = None
    if captions:
        w0_text = "" if run.static_mesh is None else " W0: the mesh force at X0 (" + ", ".join(
            f"{name + ' ' if n > 1 else ''}{float(w):.4g} N"
            for name, w in zip(run.meshes, run.static_mesh, strict=True)) + ")."
        torque = num_attr(run.attrs, "torque")
        under = "" if torque is None else f" under {torque:.4g} N m"
        import textwrap

        caption = textwrap.fill(
            "TE = r_b1 \u03b81 + r_b2 \u03b82 at the gears of a mesh, " + "; ".join(captions)
            + f". That mean holds the deflection{under}, the shafts' torsional wind-up "
            "included (the dashed line: the TE at the static solution X0); the part about it "
            "is the dynamic TE." + w0_text, int(11 * fig.get_figwidth()))
    if len(handles) > 1 or caption:
        fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=9,
                   frameon=False, title=caption, title_fontsize=9.5)
    for ax in axes.flat:
        ax.grid(True, lw=0.4, alpha=0.5)
        ax.ticklabel_format(axis="y", useOffset=False)
    return fig


_DRAW = {"orbits.png": _orbits, "bearing_forces.png": _bearing_forces,
         "spectra.png": _spectra, "mesh.png": _mesh}


def make_run_figures(results: dict, window: str | None = None) -> dict:
    """The run figures (matplotlib Figures, by file name) of what
    :func:`orchestrator.run.results.read_results` returns, over the stored case's window or
    ``window`` (:data:`fmu_src.case.FIELDS` ``simulation.window``); the caller closes them.
    Raises ValueError below 2 time steps, or for a window that is not one or is longer than
    the run."""
    plt = pyplot()
    run = RunData(results, window)
    figures = {}
    with plt.rc_context({"font.size": 10, "axes.titlesize": 11, "axes.labelsize": 10}):
        try:
            for name in RUN_FIGURES:
                figures[name] = _DRAW[name](plt, run)
            if speed_profile(run.case).varies:
                figures["run_up.png"] = draw_run_up(plt, run)
        except BaseException:
            for fig in figures.values():
                plt.close(fig)
            raise
    return figures


def run_figures(path, out_dir=None, window: str | None = None) -> list[Path]:
    """Write :data:`RUN_FIGURES` of the results file ``path`` (module docstring) into
    ``out_dir`` (default: the folder beside the file named after its stem), removing those
    PNGs left there by an earlier call first; returns the paths written. ``window``: as
    :func:`make_run_figures`. Raises ValueError if the file holds fewer than 2 time steps."""
    plt = pyplot()
    path = Path(path)
    out_dir = path.with_suffix("") if out_dir is None else Path(out_dir)
    figures = make_run_figures(read_results(path), window)
    out_dir.mkdir(parents=True, exist_ok=True)
    for name in RUN_FIGURES + _OLD_FIGURES:
        (out_dir / name).unlink(missing_ok=True)
    written = []
    try:
        for name, fig in figures.items():
            written.append(out_dir / name)
            fig.savefig(written[-1], dpi=DPI)
    finally:
        for fig in figures.values():
            plt.close(fig)
    return written
