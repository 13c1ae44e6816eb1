"""Figures from a results file, and the normalised spectrum of Fig. 7."""

import json

import numpy as np

from orchestrator.plots import basic_figures, normalised_spectrum
from orchestrator.results import ResultsWriter


def test_spectrum_lines_at_rotation_and_mesh_orders():
    f_rot, z, dt = 51.7, 26, 1e-5
    t = np.arange(0, 20 / f_rot, dt)
    sig = 100 + 3 * np.cos(2 * np.pi * f_rot * t) + 1 * np.cos(2 * np.pi * z * f_rot * t + 0.3)
    f, a = normalised_spectrum(sig, dt, f_rot)
    peaks = f[np.argsort(a)[-2:]]
    np.testing.assert_allclose(sorted(peaks), [1.0, z], atol=0.06)
    assert abs(a[np.argmin(abs(f - z))] - 1 / 3) < 0.02  # amplitudes 3 and 1


def test_basic_figures_are_written(tmp_path):
    path = tmp_path / "r.h5"
    channels = {"journal_position": ((4, 2), "m", "journal positions"),
                "bearing_force": ((4, 2), "N", "film forces"),
                "mesh_force": ((), "N", "total mesh force")}
    with ResultsWriter(path, channels, attrs={"clearance": json.dumps([1.5e-4] * 4)}) as w:
        for k in range(200):
            ph = 0.1 * k
            j = np.tile([5e-5 * np.cos(ph), 5e-5 * np.sin(ph)], (4, 1))
            w.append(time=k * 1e-4, journal_position=j, bearing_force=np.full((4, 2), 10.0 + ph),
                     mesh_force=4500 + np.sin(ph))
    paths = basic_figures(path, tmp_path / "fig")
    assert [p.name for p in paths] == ["orbits.png", "bearing_force.png", "mesh_force.png"]
    assert all(p.stat().st_size > 5000 for p in paths)
