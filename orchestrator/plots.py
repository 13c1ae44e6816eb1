"""Figures from a results file: orbits in the clearance circle, bearing force norm, mesh force.

Channels read (written by the runner, :data:`orchestrator.run.CHANNELS`): ``time`` [s],
``journal_position`` (4, 2) [m], ``bearing_force`` (4, 2) [N], ``mesh_force`` [N]; root
attribute ``clearance`` (4 values, m, JSON) for the clearance circles.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from orchestrator.results import read_results

__all__ = ["basic_figures", "normalised_spectrum", "pyplot"]


def pyplot():
    """matplotlib.pyplot on the file-only Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def normalised_spectrum(signal, dt: float, rotation_frequency: float):
    """One-sided amplitude spectrum on the paper's normalised axis (Fig. 7, 15).

    Returns (f_tilde, amplitude / max amplitude), f_tilde = f / rotation_frequency, the mean
    removed, so a line at f_tilde = 1 is once per revolution and at Z the mesh frequency.
    """
    x = np.asarray(signal, dtype=float)
    x = x - x.mean()
    amp = np.abs(np.fft.rfft(x)) * 2.0 / len(x)
    f = np.fft.rfftfreq(len(x), dt) / rotation_frequency
    return f, amp / max(amp.max(), 1e-300)


def basic_figures(results_path, out_dir, last: float | None = None) -> list[Path]:
    """Orbits of the four journals (clearance units), bearing force norms, mesh force.

    ``last`` [s] limits the orbit and force plots to the end of the run (steady state).
    """
    plt = pyplot()
    r = read_results(results_path)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    t = r["time"]
    sel = slice(None) if last is None else t >= t[-1] - last
    clearance = np.asarray(json.loads(r["attrs"]["clearance"]))
    paths = []

    fig, axes = plt.subplots(1, 4, figsize=(14, 3.8), constrained_layout=True)
    circle = np.linspace(0.0, 2.0 * np.pi, 361)
    for b, ax in enumerate(axes):
        ax.plot(np.cos(circle), np.sin(circle), "k-", lw=0.8)
        ax.plot(r["journal_position"][sel, b, 0] / clearance[b],
                r["journal_position"][sel, b, 1] / clearance[b],
                lw=0.6)
        ax.set_aspect("equal")
        ax.set_xlim(-1.05, 1.05)
        ax.set_ylim(-1.05, 1.05)
        ax.set_title(f"bearing {b + 1}")
        ax.set_xlabel("s / C")
    axes[0].set_ylabel("t / C")
    paths.append(out_dir / "orbits.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(8, 3.5), constrained_layout=True)
    for b in range(4):
        ax.plot(t[sel], np.hypot(*r["bearing_force"][sel, b].T), lw=0.7,
                label=f"bearing {b + 1}")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("||F_b|| [N]")
    ax.legend()
    paths.append(out_dir / "bearing_force.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(8, 3.5), constrained_layout=True)
    ax.plot(t[sel], r["mesh_force"][sel], lw=0.7)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("total mesh force [N]")
    paths.append(out_dir / "mesh_force.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)
    return paths
