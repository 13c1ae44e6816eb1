"""The figures of docs/rotordynamics.md: ``python docs/figures/rotordynamics.py`` (from the
repository; about a minute).

The checks' references are the tests' (``tests/gear_fmu/test_gyroscopic.py``,
``tests/gear_fmu/test_stability.py``): one home for each closed form and for the published
rotor. Writes ``docs/figures/rotordynamics_*.png`` and prints the numbers the page quotes.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from gear_fmu.modal.whirl import stability_threshold, whirl  # noqa: E402
from orchestrator.figures.base import pyplot  # noqa: E402
from tests.gear_fmu import test_gyroscopic as gyro  # noqa: E402
from tests.gear_fmu import test_stability as stab  # noqa: E402

OUT = ROOT / "docs" / "figures"
MARKERS = {"forward": "^", "backward": "v", "mixed": "o", "none": "s"}


def friswell(plt) -> None:
    """Example 5.9.1 of Friswell et al. (2010): its six lowest whirl frequencies over speed."""
    k, m, g, keep = gyro.friswell_rotor()
    nodes = SimpleNamespace(n_nodes=7, node_shaft=np.zeros(7, dtype=int), mass=m)
    rpm = np.linspace(0.0, 6000.0, 61)
    fig, ax = plt.subplots(figsize=(8, 5.5), constrained_layout=True)
    for n in rpm[1:]:
        freq, shapes = gyro.whirl_modes(k, m, g, n * math.pi / 30.0, keep)
        _, labels = whirl(nodes, shapes[:, :6], [1.0])
        for f, label in zip(freq[:6], labels, strict=True):
            ax.plot(n, f, MARKERS[label], color="tab:blue" if label == "forward"
                    else "tab:orange", ms=4)
    for n, published in ((0.0, gyro.FRISWELL_0), (4000.0, gyro.FRISWELL_4000)):
        ax.plot([n] * 6, published, "o", mfc="none", mec="k", ms=10)
        if n:
            freq, _ = gyro.whirl_modes(k, m, g, n * math.pi / 30.0, keep)
            print("Friswell 5.9.1 at 4000 rpm [rad/s]:", np.round(freq[:6], 2), "published",
                  published, "largest relative difference",
                  f"{np.max(np.abs(freq[:6] / published - 1)):.1e}")
    ax.plot(rpm, rpm * math.pi / 30.0, ":", color="k", label="1× (synchronous)")
    ax.plot([], [], "^", color="tab:blue", label="forward whirl (this code)")
    ax.plot([], [], "v", color="tab:orange", label="backward whirl (this code)")
    ax.plot([], [], "o", mfc="none", mec="k", ms=10, label="Friswell et al. (2010), Ex. 5.9.1")
    ax.set(xlabel="shaft speed [rpm]", ylabel="whirl frequency [rad/s]", ylim=(0, 1000),
           title="Two discs on a 1.5 m shaft, bearings 1 MN/m: whirl frequencies over speed")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", fontsize=9)
    fig.savefig(OUT / "rotordynamics_friswell.png", dpi=110)
    plt.close(fig)


def overhung(plt) -> None:
    """An overhung disc on a massless cantilever: this code against the closed form."""
    k, m, g, keep = gyro.overhung_model()
    spins = np.linspace(0.0, 3000.0, 31)
    fig, ax = plt.subplots(figsize=(8, 5.5), constrained_layout=True)
    worst = 0.0
    for spin in spins:
        freq, _ = gyro.whirl_modes(k, m, g, spin, keep)
        expected = gyro.overhung_closed_form(spin)
        exact = expected["forward"] + expected["backward"]
        for sense, colour in (("forward", "tab:blue"), ("backward", "tab:orange")):
            roots = expected[sense]
            ax.plot([spin] * len(roots), roots, "_", color=colour, ms=14, mew=2)
        ax.plot([spin] * 4, freq[:4], ".", color="k", ms=5)
        worst = max(worst, float(np.max(np.abs(freq[:4] / sorted(exact) - 1))))
    print(f"overhung disc: largest relative difference to the closed form {worst:.1e}")
    ax.plot(spins, spins, ":", color="k", label="1×")
    ax.plot([], [], "_", color="tab:blue", ms=14, mew=2, label="closed form, forward")
    ax.plot([], [], "_", color="tab:orange", ms=14, mew=2, label="closed form, backward")
    ax.plot([], [], ".", color="k", label="this code (3 Timoshenko elements + disc)")
    ax.set(xlabel="spin Ω [rad/s]", ylabel="whirl frequency [rad/s]", yscale="log",
           title="Overhung disc (5 kg, r = 150 mm) on a massless cantilever (300 mm, Ø 25 mm)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=9)
    fig.savefig(OUT / "rotordynamics_overhung.png", dpi=110)
    plt.close(fig)


def stability(plt) -> None:
    """A rigid rotor on two short bearings: the least damping ratio over speed."""
    expected = stab.closed_form_threshold()
    speeds = np.arange(300.0, 2050.0, 50.0)
    zetas = stab.damping_ratios(speeds)
    found = stability_threshold(speeds, zetas)
    print(f"stability threshold: closed form {expected:.2f} rad/s, this code {found:.2f} rad/s "
          f"({found / expected - 1:+.1e})")
    fig, ax = plt.subplots(figsize=(8, 5), constrained_layout=True)
    ax.plot(speeds, [min(z) for z in zetas], "o-", ms=4, label="least damping ratio (this code)")
    ax.axhline(0.0, color="k", lw=0.8)
    ax.axvline(expected, color="tab:red", ls="--",
               label=f"Lund's closed form, short bearing: {expected:.1f} rad/s")
    ax.axvline(found, color="tab:blue", ls=":",
               label=f"threshold found (interpolated): {found:.1f} rad/s")
    ax.set(xlabel="shaft speed Ω [rad/s]", ylabel="damping ratio ζ [-]",
           title="Rigid rotor, 20 kg per bearing, two short plain bearings\n"
                 "(D 50 mm, L 20 mm, c 50 µm, 0.02 Pa s): the onset of oil whirl")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=9)
    fig.savefig(OUT / "rotordynamics_stability.png", dpi=110)
    plt.close(fig)


def main() -> int:
    OUT.mkdir(parents=True, exist_ok=True)
    plt = pyplot()
    friswell(plt)
    overhung(plt)
    stability(plt)
    print(f"figures in {OUT}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
