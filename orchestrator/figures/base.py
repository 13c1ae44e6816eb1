"""What the figures of a run share: matplotlib without a display, the title built from a results
file's attributes, the arrays, train and windows of a run (:class:`RunData`) and the bearings'
styles
(:mod:`orchestrator.figures.run` draws the run's figures with them, and
:mod:`orchestrator.figures.sweep`, :mod:`orchestrator.analysis.campbell` and
:mod:`orchestrator.studies.reproduce.figures` use :func:`pyplot`).
"""

from __future__ import annotations

import json
import math

import numpy as np

from orchestrator.analysis.metrics import steady_window

__all__ = ["AMPLITUDE_LABEL", "BEARING_STYLE", "DPI", "FIGSIZE", "UM", "RunData",
           "bearing_style", "num_attr", "order_label", "pyplot", "run_title", "text_attr",
           "titled_figure"]

FIGSIZE = (11, 8)
DPI = 120
UM = 1e6
#: colour, line style, marker of the bearings, in turn along the case's bearing order: the
#: bearings of a shaft often coincide (the paper's 1/2 and 3/4), so every second one is dashed
#: with open markers offset by half a marker step
BEARING_STYLE = [("C0", "-", "o"), ("C1", "--", "s"), ("C2", "-", "^"), ("C3", "--", "v"),
                 ("C4", "-", "D"), ("C5", "--", "P"), ("C6", "-", "X"), ("C8", "--", "<")]
#: the amplitude axis of every bearing-force spectrum
#: (:func:`orchestrator.analysis.spectrum.order_spectrum`)
AMPLITUDE_LABEL = "amplitude [N] (peak)"


def bearing_style(b: int) -> tuple[str, str, str]:
    """:data:`BEARING_STYLE` of the bearing at place ``b`` (0-based) of the case's order."""
    return BEARING_STYLE[b % len(BEARING_STYLE)]


def order_label(shaft: str = "pinion") -> str:
    """The order axis of a spectrum: cycles per revolution of the ``shaft``."""
    return f"order [1/{shaft} rev]"


def pyplot():
    """matplotlib.pyplot on the file-only Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


# ---------------------------------------------------------------------------- attributes


def num_attr(attrs: dict, key: str, default=None):
    """A numeric root attribute as float / float array (older files: JSON text)."""
    value = attrs.get(key)
    if value is None or (isinstance(value, str) and not value.strip()):
        return default
    if isinstance(value, str):
        try:
            value = json.loads(value)
        except ValueError:
            return default
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return default
    return float(arr) if arr.ndim == 0 else arr


def text_attr(attrs: dict, key: str, default: str = "?") -> str:
    value = attrs.get(key, default)
    return value.decode() if isinstance(value, bytes) else str(value)


def run_title(attrs: dict, steps: int, what: str = "") -> str:
    """Two-line figure title from a results file's root attributes: what the figure shows,
    the case, bearing model and mode; input speed (rad/s and rpm), torque, unbalance, and
    "(incomplete run: N steps)" unless the file is marked complete."""
    head = f"{text_attr(attrs, 'case')} - {text_attr(attrs, 'bearing_model')} bearings, " \
           f"{text_attr(attrs, 'mode')}"
    parts = []
    speed = num_attr(attrs, "speed")
    if speed is not None:
        parts.append(f"input speed {speed:.4g} rad/s ({speed * 30.0 / math.pi:.4g} rpm)")
    torque = num_attr(attrs, "torque")
    if torque is not None:
        parts.append(f"torque {torque:.4g} N m")
    unbalance = num_attr(attrs, "unbalance")
    if unbalance is not None:
        u = np.atleast_1d(unbalance) * 1e3
        if u.size and np.all(u == u[0]):
            parts.append(f"unbalance {u[0]:.3g} mm (every gear)")
        else:
            parts.append("unbalance " + " / ".join(f"{v:.3g}" for v in u) + " mm (gears in the "
                         "case's order)")
    tail = "" if bool(attrs.get("complete", False)) else f" (incomplete run: {steps} steps)"
    return (f"{what}: " if what else "") + head + "\n" + ", ".join(parts) + tail


class RunData:
    """The arrays, the train and the windows the figures of a run share: the bearings,
    shafts, meshes and gears of the case stored in the results file (its order and names),
    each shaft's speed ratio to the input, the report's window (the stored case's, or
    ``window``: its ``simulation.window`` replaced)."""

    def __init__(self, results: dict, window: str | None = None):
        from fmu_src.description import layout
        from orchestrator.analysis.metrics import stored_case

        self.attrs = results["attrs"]
        self.time = np.asarray(results["time"], dtype=float)
        self.steps = self.time.size
        if self.steps < 2:
            raise ValueError(f"the file has {self.steps} time step(s): nothing to plot yet")
        if "case_toml" not in self.attrs:
            raise ValueError("the file stores no case (attribute case_toml): its bearings, "
                             "shafts and meshes are unknown")
        from fmu_src.case import CaseError

        try:
            self.case = stored_case(self.attrs, window=window)
        except CaseError as exc:
            if window is None:
                raise
            # a window that is none: the one the caller gave
            raise ValueError(str(exc).replace("(stored case)", "(--window)")) from None
        lay = self.layout = layout(self.case)
        self.bearings = list(lay.bearing_names)
        self.bearing_shaft = [b.shaft for b in lay.bearings]
        self.shafts = [s.name for s in lay.shafts]
        self.meshes = list(lay.mesh_names)
        self.input_shaft = lay.drive.input_shaft
        self.ratios = {s.name: float(r) for s, r in zip(lay.shafts, lay.ratios, strict=True)}
        self.mesh_orders = []  # each mesh's frequency per input revolution
        self.mesh_teeth = []  # (driver, driven) teeth of each mesh
        for driver, driven in lay.drivers:
            g = lay.gear(driver)
            self.mesh_orders.append(g.teeth * self.ratios[g.shaft])
            self.mesh_teeth.append((g.teeth, lay.gear(driven).teeth))
        self.journal = np.asarray(results["journal_position"], dtype=float)
        self.force = np.asarray(results["bearing_force"], dtype=float)
        self.force_norm = np.hypot(self.force[..., 0], self.force[..., 1])
        mesh = np.asarray(results["mesh_force"], dtype=float)
        self.mesh = mesh.reshape(self.steps, -1)  # (steps, n_meshes)
        te = results.get("transmission_error")
        self.te = None if te is None else np.asarray(te, dtype=float).reshape(self.steps, -1)
        self.dt = float(np.median(np.diff(self.time)))
        self.speed = abs(float(lay.drive.speed)) or 2.0 * math.pi  # rad/s, the input's
        self.input_hz = self.speed / (2.0 * math.pi)
        self.input_rev = 1.0 / self.input_hz
        self.clearance = np.array([b.clearance for b in lay.bearings])
        self.static_journal = num_attr(self.attrs, "static_journal")
        static_mesh = num_attr(self.attrs, "static_mesh_force")
        self.static_mesh = None if static_mesh is None else np.atleast_1d(static_mesh)
        static_te = num_attr(self.attrs, "static_transmission_error")
        self.static_te = None if static_te is None else np.atleast_1d(static_te)

    def title(self, what: str) -> str:
        return run_title(self.attrs, self.steps, what)

    def shaft_hz(self, shaft: str) -> float:
        """Rotation frequency of a shaft [Hz]."""
        return self.input_hz * self.ratios[shaft]

    def groups(self) -> list[tuple[str, list[int]]]:
        """``(shaft, [bearing places])`` of every shaft, in the case's order."""
        return [(s, [b for b, on in enumerate(self.bearing_shaft) if on == s])
                for s in self.shafts]

    def long_window(self) -> tuple[np.ndarray, str, float]:
        """The window of the report of ``gsb run``: the last revolution of the slowest shaft,
        the last half of a shorter run (:func:`orchestrator.analysis.metrics.report_window`):
        mask, name and duration [s]."""
        from orchestrator.analysis.metrics import report_window

        duration, kind = report_window(self.case, self.time)
        return steady_window(self.time, duration), kind, duration

    def short_window(self) -> tuple[np.ndarray, str]:
        """The last revolution of the input shaft (the whole run if shorter)."""
        if self.time[-1] - self.time[0] >= self.input_rev * (1 - 1e-9):
            return steady_window(self.time, self.input_rev), "its last revolution"
        return np.ones(self.steps, dtype=bool), "whole run, shorter than a revolution"


def titled_figure(plt, run: RunData, what: str, **kw):
    kw.setdefault("figsize", FIGSIZE)
    fig = plt.figure(layout="constrained", **kw)
    fig.suptitle(run.title(what), fontsize=12)
    return fig
