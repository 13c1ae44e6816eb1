"""Figures of a sweep file (``gsb sweep``, :mod:`orchestrator.sweeps.runner`).

:func:`sweep_figures` draws, against the input speed when the sweep varies it (else against
the first varied field):

* ``R_ptp.png``: the dynamic factor R of each mesh, one curve per mesh and bearing model (and
  per value of the other varied fields), and the peak-to-peak of ||F_b|| at every bearing, a
  panel per curve; the bearings, named as in the case, differ in colour, line style and
  marker, so bearings that coincide (1 and 2, 3 and 4 in the spur case) both stay visible;
* ``waterfall_bearing_<name>.png``, one per shaft for its first bearing (a bearing named by
  a number without the ``_``: the paper's ``waterfall_bearing1.png`` and
  ``waterfall_bearing3.png``): the order spectrum of ||F_b||
  at that bearing against the swept value, in orders of its shaft (peak amplitude, the scale
  of the run figures: the spectra the points stored,
  :func:`orchestrator.sweeps.runner.point_spectrum`; log colour scale), a panel per curve,
  with the shaft's 1x and every mesh's first three harmonics marked.

Every figure is titled with the case, the bearing models and the operating values the sweep
keeps fixed.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from orchestrator.figures.base import AMPLITUDE_LABEL, BEARING_STYLE, order_label

__all__ = ["BEARING_STYLES", "sweep_figures", "waterfall_data"]

#: matplotlib styles of the bearings in the case's order (in turn): the colours, lines and
#: markers of the run figures (:data:`orchestrator.figures.base.BEARING_STYLE`), every second
#: bearing with open markers, so that bearings that coincide both stay visible
BEARING_STYLES = tuple(
    {"color": colour, "ls": ls, "marker": marker, "ms": 8, "lw": 1.6,
     "mfc": "none" if b % 2 else colour}
    for b, (colour, ls, marker) in enumerate(BEARING_STYLE))

#: the operating fields a sweep varies most (and their keys in sweep files of the
#: single-stage schema) -> (axis name, short name)
_NAMES = {"drive.speed": ("input speed", "speed"), "operation.speed": ("pinion speed", "speed"),
          "drive.torque": ("input torque", "torque"),
          "operation.torque": ("input torque", "torque"),
          "gears.*.unbalance": ("unbalance e_mu", "unbalance"),
          "operation.unbalance": ("unbalance e_mu", "unbalance")}
_SPEEDS = ("drive.speed", "operation.speed")


def _axis_label(key: str, unit: str) -> str:
    name = _NAMES.get(key, (key, key))[0]
    return f"{name} [{unit}]" if unit else name


def _short(key: str, value: float, unit: str) -> str:
    name = _NAMES.get(key, (key, key))[1]
    return f"{name} {value:g}{' ' + unit if unit not in ('', '1') else ''}"


def _fixed(case, keys) -> str:
    """The operating values the sweep keeps fixed."""
    varied = {_NAMES[k][1] for k in keys if k in _NAMES}
    parts = []
    if "speed" not in varied:
        w = case["drive.speed"]
        parts.append(f"input speed {w:g} rad/s ({w * 30 / math.pi:.0f} rpm)")
    if "torque" not in varied:
        parts.append(f"torque {case['drive.torque']:g} N m")
    if "unbalance" not in varied:
        e = [case[f"gears.{g}.unbalance"] * 1e3 for g in case.names("gears")]
        if len(set(e)) == 1:
            parts.append(f"unbalance {e[0]:g} mm (every gear)")
        else:
            parts.append(f"unbalance {' / '.join(f'{x:g}' for x in e)} mm (gears "
                         f"{', '.join(case.names('gears'))})")
    return ", ".join(parts)


def _edges(x: np.ndarray) -> np.ndarray:
    """Cell edges around sorted centres (pcolormesh)."""
    x = np.asarray(x, dtype=float)
    if x.size == 1:
        h = 0.05 * abs(x[0]) or 0.5
        return np.array([x[0] - h, x[0] + h])
    mid = 0.5 * (x[1:] + x[:-1])
    return np.r_[x[0] - (mid[0] - x[0]), mid, x[-1] + (x[-1] - mid[-1])]


def _rows(x: np.ndarray, amp: np.ndarray) -> tuple[np.ndarray, np.ma.MaskedArray]:
    """Row edges and values of a waterfall: a band of 0.8 of the smallest spacing about each
    computed value of the sweep, nothing (masked rows) between two: no cell spans a value
    that was not computed."""
    x = np.asarray(x, dtype=float)
    gap = float(np.min(np.diff(x))) if x.size > 1 else 0.0
    half = 0.4 * (gap if gap > 0.0 else (0.1 * abs(x[0]) or 1.0))
    edges = np.column_stack([x - half, x + half]).ravel()
    rows = np.full((2 * x.size - 1, amp.shape[1]), np.nan)
    rows[::2] = amp
    return edges, np.ma.masked_invalid(rows)


def _groups(points, keys, units, ix):
    """Successful points by (bearing model, values of the other varied fields), each sorted
    by the swept value: ``{label: [points]}``."""
    out: dict[str, list] = {}
    for p in points:
        if p["error"] is not None:
            continue
        others = [_short(k, p["values"][j], units[j]) for j, k in enumerate(keys) if j != ix]
        label = ", ".join([str(p["bearing"]), *others])
        out.setdefault(label, []).append(p)
    for label in out:
        out[label].sort(key=lambda p: p["values"][ix])
    return out


def _grid(plt, n: int, ncols_max: int, width: float, height: float, **kw):
    ncols = min(n, ncols_max)
    nrows = math.ceil(n / ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(max(width * ncols, 9.5),
                                                    height * nrows + 0.8),
                             constrained_layout=True, squeeze=False, **kw)
    flat = list(axes.ravel())
    for ax in flat[n:]:
        ax.set_visible(False)
    return fig, flat[:n]


def waterfall_data(points, ix: int, bearing: int = 0, ratio: float = 1.0):
    """What a waterfall panel draws for one curve of ``points`` (sorted by the swept value,
    index ``ix`` of ``values``): the swept values (k,), the orders (m,) of the first point's
    spectrum without order 0 (the mean) and the peak amplitudes (k, m) [N] of ||F_b|| at
    ``bearing`` (its place in the case's order), each point's stored spectrum read at those
    orders. The points store orders of the input shaft; ``ratio``, the speed of the
    bearing's shaft over the input speed, turns them into orders of that shaft
    (``input order / ratio``)."""
    orders = np.asarray(points[0]["spectrum_orders"], dtype=float)
    amp = np.array([np.interp(orders, p["spectrum_orders"], p["spectrum"][bearing])
                    for p in points])
    return np.array([p["values"][ix] for p in points]), orders[1:] / ratio, amp[:, 1:]


def _window_name(attrs: dict) -> str:
    """The window a sweep file's figures are taken over (its ``window`` attribute; a file of
    an earlier version: its ``steady_periods``)."""
    if attrs.get("window"):
        return str(attrs["window"])
    return f"last {attrs['steady_periods']} mesh periods"


def sweep_figures(path, out_dir=None) -> list[Path]:
    """The PNG figures of a sweep file (module docstring) in ``out_dir`` (default: the folder
    named after the file's stem, beside it); returns their paths ([] when no point
    succeeded)."""
    from matplotlib.colors import LogNorm

    from fmu_src.description import layout
    from orchestrator.analysis.campbell import order_lines
    from orchestrator.analysis.metrics import stored_case
    from orchestrator.figures.base import pyplot
    from orchestrator.sweeps.file import read_sweep, read_sweep_attrs

    path = Path(path)
    out_dir = path.parent / path.stem if out_dir is None else Path(out_dir)
    attrs = read_sweep_attrs(path)
    if attrs.get("kind") != "sweep":
        raise ValueError(f"{path}: not a sweep file (kind = {attrs.get('kind')!r})")
    keys = list(attrs["vary_keys"])
    units = list(attrs["vary_units"])
    if not keys:
        raise ValueError(f"{path}: the sweep varies no field")
    case = stored_case(attrs, str(path))
    lay = layout(case)
    lines = order_lines(case)
    names = list(lay.bearing_names)
    meshes = list(lay.mesh_names)
    ix = next((keys.index(k) for k in _SPEEDS if k in keys), 0)
    points = read_sweep(path)
    groups = _groups(points, keys, units, ix)
    if not groups:
        return []
    out_dir.mkdir(parents=True, exist_ok=True)
    plt = pyplot()
    xlabel = _axis_label(keys[ix], units[ix])
    bearings = ", ".join(attrs["bearings"])
    n_models = len(attrs["bearings"])
    fixed = _fixed(case, keys)
    head = (f"{attrs['case']}: bearing model{'s' * (n_models > 1)} {bearings}"
            + (f"; {fixed}" if fixed else ""))
    window = f"{attrs['periods']} mesh periods per run, window: {_window_name(attrs)}"
    failed = sum(p["error"] is not None for p in points)
    if failed:
        window += f"; {failed} failed point{'s' * (failed > 1)} left out"
    paths = []

    # (1) R of each mesh and the bearing-force peak-to-peak
    fig, axes = _grid(plt, 1 + len(groups), 3, 5.0, 4.0)
    ax = axes[0]
    k = 0
    for label, pts in groups.items():
        x = [p["values"][ix] for p in pts]
        r = np.array([np.atleast_1d(p["R"]) for p in pts])
        for m in range(r.shape[1]):
            name = label + (f", mesh {meshes[m]}" if len(meshes) > 1 else "")
            ax.plot(x, r[:, m], ["o-", "s--", "^-.", "v:"][m % 4], color=f"C{k % 10}",
                    label=name)
            k += 1
    ax.set_xlabel(xlabel)
    ax.set_ylabel("R = max dynamic / static mesh load [1]")
    ax.set_title("dynamic factor R" + (" of each mesh" if len(meshes) > 1 else ""))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ptp_axes = axes[1:]
    for ax, (label, pts) in zip(ptp_axes, groups.items(), strict=True):
        x = [p["values"][ix] for p in pts]
        ptp = np.array([p["force_ptp"] for p in pts])
        for b in range(ptp.shape[1]):
            ax.plot(x, ptp[:, b], label=f"bearing {names[b]}",
                    **BEARING_STYLES[b % len(BEARING_STYLES)])
        ax.set_xlabel(xlabel)
        ax.set_ylabel("peak-to-peak ||F_b|| [N]")
        ax.set_title(f"bearing forces: {label}", fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=1 + (ptp.shape[1] > 4))
    top = max(float(np.max([p["force_ptp"] for p in pts])) for pts in groups.values())
    for ax in ptp_axes:
        ax.set_ylim(0.0, 1.08 * top if top > 0 else 1.0)
    _suptitle(fig, f"{head}\nR and bearing-force peak-to-peak; {window}")
    paths.append(_save(fig, out_dir / "R_ptp.png", plt))

    # (2) waterfalls: order spectrum of ||F_b|| at each shaft's first bearing against the
    # swept value, in orders of that shaft
    for shaft, ratio in zip(lines["shafts"], lines["shaft_ratios"], strict=True):
        on = [b for b, spec in enumerate(lay.bearings) if spec.shaft == shaft]
        if not on:
            continue
        b = on[0]
        fig, axes = _grid(plt, len(groups), 2, 6.5, 4.6)
        spectra = {label: waterfall_data(pts, ix, b, ratio) for label, pts in groups.items()}
        peak = max((float(a.max()) for _, _, a in spectra.values() if a.size), default=0.0)
        norm = LogNorm(vmin=peak * 1e-4, vmax=peak) if peak > 0 else None
        mesh = None
        marks = [(1.0, "1x")]
        for mesh_name, order in zip(lines["meshes"], lines["mesh_orders"], strict=True):
            q = order / ratio
            tag = f"{mesh_name} " if len(meshes) > 1 else ""
            marks += [(kq * q, f"{tag}{kq}x mesh = {kq * q:.4g}") for kq in (1, 2, 3)]
        for ax, (label, (x, orders, amp)) in zip(axes, spectra.items(), strict=True):
            if orders.size == 0:
                ax.set_title(f"{label}: no spectrum (window too short)", fontsize=10)
                continue
            top = orders[-1] + 0.5 * (orders[1] - orders[0] if orders.size > 1 else 1.0)
            orders, amp = _pool(orders, amp, 300)  # lines narrower than a pixel would vanish
            edges, rows = _rows(x, np.maximum(amp, peak * 1e-6))
            mesh = ax.pcolormesh(_edges(orders), edges, rows, norm=norm, cmap="viridis",
                                 shading="flat")
            if x.size <= 16:  # the values computed, each a band
                ax.set_yticks(x, [f"{v:.4g}" for v in x], fontsize=8)
            shown = [(q, text) for q, text in marks if q <= top]
            sec = ax.secondary_xaxis("top")
            sec.set_xticks([q for q, _ in shown], [text for _, text in shown], fontsize=8,
                           rotation=30 if len(shown) > 4 else 0, ha="left")
            sec.tick_params(direction="inout", length=8)
            ax.set_xlim(0.0, top)
            ax.set_xlabel(order_label(shaft))
            ax.set_ylabel(xlabel)
            ax.set_title(label, fontsize=10)
        if mesh is not None:
            fig.colorbar(mesh, ax=axes, label=f"bearing {names[b]}: ||F_b|| {AMPLITUDE_LABEL}")
        _suptitle(fig, f"{head}\norder spectrum of the force norm of bearing {names[b]} "
                  f"(shaft {shaft}; peak amplitude, Hann window); {window}")
        paths.append(_save(fig, out_dir / _waterfall_name(names[b]), plt))
    return paths


def _waterfall_name(bearing: str) -> str:
    """``waterfall_bearing1.png`` for a bearing numbered as the paper's, else
    ``waterfall_bearing_<name>.png``."""
    return f"waterfall_bearing{'' if bearing.isdigit() else '_'}{bearing}.png"


def _pool(orders: np.ndarray, amp: np.ndarray, cells: int):
    """The spectra on at most ``cells`` columns: the largest amplitude of each group of
    neighbouring bins (a waterfall shows where the lines are)."""
    k = max(1, math.ceil(orders.size / cells))
    if k == 1:
        return orders, amp
    n = math.ceil(orders.size / k) * k
    padded = np.zeros((amp.shape[0], n))
    padded[:, :orders.size] = amp
    step = orders[1] - orders[0]
    centres = orders[0] + step * (np.arange(n // k) * k + 0.5 * (k - 1))
    return centres, padded.reshape(amp.shape[0], -1, k).max(axis=2)


def _suptitle(fig, text: str) -> None:
    """A title wrapped to the figure's width (11 pt: about 10 characters per inch)."""
    import textwrap

    chars = int(10 * fig.get_figwidth())
    fig.suptitle("\n".join(textwrap.fill(line, chars) for line in text.splitlines()),
                 fontsize=11)


def _save(fig, path: Path, plt) -> Path:
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
