"""What the figures of a run share: matplotlib without a display, the title built from a results
file's attributes, the arrays and windows of a run (:class:`RunData`) and the bearings' styles
(:mod:`orchestrator.figures.run` draws the run's figures with them, and
:mod:`orchestrator.figures.sweep`, :mod:`orchestrator.analysis.campbell` and
:mod:`orchestrator.studies.reproduce.figures` use :func:`pyplot`).
"""

from __future__ import annotations

import json
import math

import numpy as np

from orchestrator.analysis.metrics import steady_window

__all__ = ["AMPLITUDE_LABEL", "BEARING_STYLE", "DPI", "FIGSIZE", "SHAFTS", "UM", "RunData",
           "num_attr", "order_label", "pyplot", "run_title", "text_attr", "titled_figure"]

FIGSIZE = (11, 8)
DPI = 120
UM = 1e6
#: colour, line style, marker of bearings 1-4: 1/2 and 3/4 coincide in the spur case, so the
#: second of each shaft is dashed with open markers offset by half a marker step
BEARING_STYLE = [("C0", "-", "o"), ("C1", "--", "s"), ("C2", "-", "^"), ("C3", "--", "v")]
SHAFTS = (("pinion shaft", (0, 1)), ("gear shaft", (2, 3)))
#: the amplitude axis of every bearing-force spectrum
#: (:func:`orchestrator.analysis.spectrum.order_spectrum`)
AMPLITUDE_LABEL = "amplitude [N] (peak)"


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
    the case, bearing model and mode; pinion speed (rad/s and rpm), torque, unbalance, and
    "(incomplete run: N steps)" unless the file is marked complete."""
    head = f"{text_attr(attrs, 'case')} - {text_attr(attrs, 'bearing_model')} bearings, " \
           f"{text_attr(attrs, 'mode')}"
    parts = []
    speed = num_attr(attrs, "speed")
    if speed is not None:
        parts.append(f"pinion speed {speed:.4g} rad/s ({speed * 30.0 / math.pi:.4g} rpm)")
    torque = num_attr(attrs, "torque")
    if torque is not None:
        parts.append(f"torque {torque:.4g} N m")
    unbalance = num_attr(attrs, "unbalance")
    if unbalance is not None:
        u = np.atleast_1d(unbalance) * 1e3
        parts.append("unbalance " + " / ".join(f"{v:.3g}" for v in u) + " mm"
                     + (" (pinion / gear)" if u.size == 2 else ""))
    tail = "" if bool(attrs.get("complete", False)) else f" (incomplete run: {steps} steps)"
    return (f"{what}: " if what else "") + head + "\n" + ", ".join(parts) + tail


class RunData:
    """The arrays and windows the figures share."""

    def __init__(self, results: dict):
        self.attrs = results["attrs"]
        self.time = np.asarray(results["time"], dtype=float)
        self.steps = self.time.size
        if self.steps < 2:
            raise ValueError(f"the file has {self.steps} time step(s): nothing to plot yet")
        self.journal = np.asarray(results["journal_position"], dtype=float)
        self.force = np.asarray(results["bearing_force"], dtype=float)
        self.force_norm = np.hypot(self.force[..., 0], self.force[..., 1])
        self.mesh = np.asarray(results["mesh_force"], dtype=float)
        te = results.get("transmission_error")
        self.te = None if te is None else np.asarray(te, dtype=float)
        self.dt = float(np.median(np.diff(self.time)))
        self.speed = abs(num_attr(self.attrs, "speed", 0.0)) or 2.0 * math.pi  # rad/s
        self.pinion_hz = self.speed / (2.0 * math.pi)
        teeth = num_attr(self.attrs, "teeth")
        self.teeth = None if teeth is None else [int(z) for z in np.rint(teeth)]
        self.pinion_rev = 1.0 / self.pinion_hz
        self.gear_rev = (None if self.teeth is None
                         else self.pinion_rev * self.teeth[1] / self.teeth[0])
        self.clearance = num_attr(self.attrs, "clearance")
        self.static_journal = num_attr(self.attrs, "static_journal")
        self.static_mesh = num_attr(self.attrs, "static_mesh_force")
        self.static_te = num_attr(self.attrs, "static_transmission_error")

    def title(self, what: str) -> str:
        return run_title(self.attrs, self.steps, what)

    def long_window(self) -> tuple[np.ndarray, str, float]:
        """The last gear revolution (the last half of a shorter run), the window of the report
        of ``gsb run`` (:func:`orchestrator.analysis.metrics.run_report`): mask, name and
        duration [s]."""
        end = self.time[-1]
        if self.gear_rev is not None and end >= self.gear_rev * (1 - 1e-9):
            return steady_window(self.time, self.gear_rev), "last gear revolution", self.gear_rev
        return steady_window(self.time, 0.5 * end), "last half of the run", 0.5 * end

    def short_window(self) -> tuple[np.ndarray, str]:
        """The last pinion revolution (the whole run if shorter)."""
        if self.time[-1] - self.time[0] >= self.pinion_rev * (1 - 1e-9):
            return steady_window(self.time, self.pinion_rev), "last pinion revolution"
        return np.ones(self.steps, dtype=bool), "whole run, shorter than a pinion revolution"


def titled_figure(plt, run: RunData, what: str, **kw):
    fig = plt.figure(figsize=FIGSIZE, layout="constrained", **kw)
    fig.suptitle(run.title(what), fontsize=12)
    return fig
