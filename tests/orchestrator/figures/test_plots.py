"""Figures of a run (orchestrator.figures.run) and ``gsb plot`` (their spectrum:
tests/orchestrator/analysis/test_spectrum.py).

The results files are synthetic, in the format orchestrator.run.runner writes (channels with a
``unit`` attribute, numeric root attributes): the paper's spur case (pinion 325 rad/s,
z = 26 / 157, clearances 150 / 150 / 110 / 110 um), orbits as ellipses around the static
point, bearing-force norms with known lines at 1x, gear 1x and 26x.
"""

import itertools
import math
import subprocess
import sys

import h5py
import numpy as np
import pytest

from fmu_src.case import load_case
from orchestrator.cli import main
from orchestrator.figures.base import pyplot, run_title
from orchestrator.figures.run import RUN_FIGURES, make_run_figures
from orchestrator.run.results import ResultsWriter, read_results
from tests.helpers import probe_env

SPEED, TEETH, TORQUE = 325.0, (26, 157), 220.0
F1 = SPEED / (2 * math.pi)  # pinion rotation [Hz]
DT = 1.0 / (32 * TEETH[0] * F1)  # 32 steps per mesh period
GEAR_REV_STEPS = 32 * TEETH[1]  # 5024
#: ||F_b|| lines [N] of bearings 1-4: (1x, gear 1x, 26x)
LINES = np.array([[150.0, 0.0, 80.0], [150.0, 0.0, 80.0],
                  [5.0, 40.0, 120.0], [5.0, 40.0, 120.0]])
X0 = np.array([[41.5, -93.4], [41.5, -93.4], [68.8, 36.6], [68.8, 36.6]]) * 1e-6


def _attrs(complete: bool) -> dict:
    return {"kind": "run", "case": "baguet2010_spur", "bearing_model": "hybrid",
            "mode": "in-process", "dt": DT, "dt_unit": "s", "speed": SPEED,
            "speed_unit": "rad/s", "speeds": np.array([SPEED, SPEED, 53.8, 53.8]),
            "mesh_teeth": np.array([TEETH]), "torque": TORQUE, "torque_unit": "N.m",
            "unbalance": np.array([6e-4, 6e-4]), "unbalance_unit": "m",
            "clearance": np.array([150e-6, 150e-6, 110e-6, 110e-6]), "clearance_unit": "m",
            "static_journal": X0, "static_journal_unit": "m",
            "static_bearing_force": np.full((4, 2), 1500.0),
            "static_mesh_force": np.array([4502.3]),
            "static_transmission_error": np.array([140.3e-6]), "complete": complete,
            "stopped_by": "", "case_toml": load_case("baguet2010_spur").to_toml()}


def _channels(steps: int) -> dict:
    t = np.arange(1, steps + 1) * DT
    w = 2 * math.pi * F1 * t
    rise = 1.0 - np.exp(-t / 0.01)  # orbits grow from X0 (a transient)
    journal = np.empty((steps, 4, 2))
    for b in range(4):
        rot = w if b < 2 else w * TEETH[0] / TEETH[1]
        journal[:, b, 0] = X0[b, 0] + rise * (10e-6 if b < 2 else 1.5e-6) * np.cos(rot)
        journal[:, b, 1] = X0[b, 1] + rise * (4e-6 if b < 2 else 2e-6) * np.sin(rot + 0.5)
    angles = np.array([1.2, 1.2, -1.0, -1.0])
    norm = 2300.0 + (LINES[:, 0] * np.cos(w[:, None] + 0.4)
                     + LINES[:, 1] * np.cos(w[:, None] * TEETH[0] / TEETH[1] + 1.0)
                     + LINES[:, 2] * np.cos(TEETH[0] * w[:, None] + 0.3))
    force = np.stack([norm * np.cos(angles), norm * np.sin(angles)], axis=-1)
    mesh = 4502.3 + 1500.0 * np.sin(TEETH[0] * w) + 300.0 * np.sin(w)
    return {"time": (t, "s"), "journal_position": (journal, "m"),
            "journal_velocity": (np.gradient(journal, DT, axis=0), "m/s"),
            "bearing_force": (force, "N"), "mesh_force": (mesh[:, None], "N"),
            "transmission_error": ((140.3e-6 + 5e-6 * np.sin(w) + 1e-6 * np.sin(26 * w))[:, None],
                                   "m"),
            "gear_node": (np.zeros((steps, 2, 2)), "m"), "iterations": (np.full(steps, 3), "1")}


def _write(path, steps: int, complete: bool):
    with h5py.File(path, "w") as f:
        for name, (data, unit) in _channels(steps).items():
            f.create_dataset(name, data=data).attrs["unit"] = unit
        for key, value in _attrs(complete).items():
            f.attrs[key] = value
    return path


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    """A complete run of 6000 steps: the last gear revolution (5024) and a transient."""
    return _write(tmp_path_factory.mktemp("run") / "spur.h5", 6000, True)


def test_run_title_names_case_model_speed_torque():
    title = run_title(_attrs(False), 300, "orbits")
    for text in ("baguet2010_spur", "hybrid", "in-process", "input speed 325 rad/s", "3104 rpm",
                 "220 N m", "unbalance 0.6 mm (every gear)", "(incomplete run: 300 steps)"):
        assert text in title
    assert "incomplete" not in run_title(_attrs(True), 6000)


def test_figures_show_the_run_and_its_lines(run_file):
    plt = pyplot()
    figures = make_run_figures(read_results(run_file))
    try:
        for fig in figures.values():
            title = fig.get_suptitle()
            assert all(s in title for s in ("baguet2010_spur", "hybrid", "325", "220"))
            assert "incomplete" not in title
        # the spectra's axes state their units: peak amplitude in N against the orders of
        # each panel's shaft (the pinion's, then the gear's)
        spectra = [ax for ax in figures["spectra.png"].axes if ax.get_ylabel()]
        assert [ax.get_ylabel() for ax in spectra] == ["amplitude [N] (peak)"] * 2
        assert [ax.get_title(loc="left") for ax in spectra] == ["shaft pinion_shaft",
                                                                "shaft gear_shaft"]
        assert spectra[0].get_xlabel().startswith("order [1/pinion_shaft rev]")
        assert spectra[-1].get_xlabel().startswith("order [1/gear_shaft rev]")
        # the gear shaft's panel marks the mesh line at its order 157, the pinion's at 26
        marks = [{round(line.get_xdata()[0], 6) for line in ax.get_lines()
                  if line.get_linestyle() == ":"} for ax in spectra]
        assert 26.0 in marks[0] and 157.0 in marks[1]
        # the least-squares amplitudes listed beside the spectra: 150, 80, 40, 120 N
        table = "\n".join(t.get_text() for ax in figures["spectra.png"].axes
                          for t in ax.texts)
        assert "last revolution of the slowest shaft gear_shaft" in table
        assert ["line", "1", "2", "3", "4"] in [row.split() for row in table.splitlines()]
        rows = {line.split()[0]: line.split()[1:] for line in table.splitlines()
                if line.split() and line.split()[0] in ("pinion_shaft_1x", "gear_shaft_1x",
                                                        "mesh_GMF")}
        np.testing.assert_allclose(np.array([rows["pinion_shaft_1x"], rows["gear_shaft_1x"],
                                             rows["mesh_GMF"]], dtype=float)[:, 2],
                                   [5, 40, 120], rtol=2e-3)
        assert rows["pinion_shaft_1x"][0] == "150" and rows["mesh_GMF"][0] == "80"
        # orbits zoomed: the last gear revolution of bearing 1 fills most of its panel,
        # titled by the bearing's name and shaft
        ax = figures["orbits.png"].axes[0]
        assert ax.get_title().startswith("bearing 1 (shaft pinion_shaft), X0 at e/C = ")
        assert np.ptp(ax.get_xlim()) < 40  # um, against a 300 um clearance diameter
    finally:
        for fig in figures.values():
            plt.close(fig)


def test_figures_of_a_file_being_written(tmp_path):
    """An incomplete file (200 steps, less than a pinion revolution) still open by its
    writer (SWMR): the rows flushed so far, titled as incomplete."""
    path = tmp_path / "live.h5"
    rows = _channels(200)
    channels = {n: (d.shape[1:], unit, n) for n, (d, unit) in rows.items() if n != "time"}
    w = ResultsWriter(path, channels, attrs=_attrs(False))
    try:
        for k in range(200):
            w.append(time=rows["time"][0][k], **{n: rows[n][0][k] for n in channels})
        w.flush()
        plt = pyplot()
        figures = make_run_figures(read_results(path))
        titles = [f.get_suptitle() for f in figures.values()]
        for fig in figures.values():
            plt.close(fig)
        assert all("(incomplete run: 200 steps)" in title for title in titles)
        assert sorted(figures) == sorted(RUN_FIGURES)  # saving them: test_gsb_plot_run_file
    finally:
        w.close(complete=True)


def test_gsb_plot_run_file(run_file, capsys):
    """``gsb plot FILE``: the four figures in the folder named after the file, stale ones
    removed, each path printed."""
    out = run_file.with_suffix("")
    out.mkdir(exist_ok=True)
    (out / "bearing_force.png").write_bytes(b"stale")  # an earlier version's figure
    assert main(["plot", str(run_file)]) == 0
    assert capsys.readouterr().out.split() == [str(out / name) for name in RUN_FIGURES]
    assert sorted(p.name for p in out.iterdir()) == sorted(RUN_FIGURES)
    assert all((out / name).stat().st_size > 20000 for name in RUN_FIGURES)


@pytest.mark.parametrize("content", [b"not hdf5\n", None])
def test_gsb_plot_bad_file(tmp_path, capsys, content):
    path = tmp_path / "bad.h5"
    if content is not None:
        path.write_bytes(content)
    assert main(["plot", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gsb plot: error: ") and str(path) in err
    assert err.count("\n") == 1 and "Traceback" not in err


def _whole_run_lines(fig, ylabel_start: str) -> dict:
    """The lines of the whole-run panel whose y label starts so, by legend label."""
    ax = next(a for a in fig.axes if a.get_title() == "whole run"
              or (a.get_ylabel().startswith(ylabel_start) and a.get_xlabel() == "time [ms]"))
    assert ax.get_ylabel().startswith(ylabel_start)
    return {line.get_label(): line for line in ax.get_lines()}


def test_mesh_figure_of_a_long_run_bins_by_pinion_revolution(tmp_path):
    """A 2048-mesh-period run (65536 steps, 78.8 pinion revolutions): ``gsb plot`` draws it
    (exit 0), the whole-run TE envelope has a point per input (pinion) revolution and is flat
    for a
    TE made of pinion orders (bins of 4 mesh periods alias against the 26-period revolution:
    their max swings with the 1x), the TE is drawn about its mean with the mean and the
    shafts' wind-up stated, and the top time labels do not run into each other."""
    path = _write(tmp_path / "long.h5", 65536, True)
    done = subprocess.run([sys.executable, "-m", "orchestrator.cli", "plot", str(path)],
                          capture_output=True, text=True, timeout=300, env=probe_env())
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "long" / "mesh.png").stat().st_size > 20_000
    plt = pyplot()
    results = read_results(path)
    te = results["transmission_error"]
    mean = te[-GEAR_REV_STEPS:].mean()  # the last gear revolution
    figures = make_run_figures(results)
    try:
        fig = figures["mesh.png"]
        lines = _whole_run_lines(fig, "TE - mean")
        label = next(k for k in lines if k.startswith("max / min per input revolution"))
        hi = lines[label].get_ydata()
        centres = lines[label].get_xdata()
        assert len(hi) == 79  # 78 whole revolutions ending at the last step, 0.77 kept
        np.testing.assert_allclose(np.diff(centres[1:]), 1e3 / F1, rtol=1e-9)
        # synthetic TE: 5 um at 1x + 1 um at 26x, whose max over a revolution is fixed
        assert np.ptp(hi[1:]) < 1e-6
        assert hi[-1] == pytest.approx((te[-32 * TEETH[0]:].max() - mean) * 1e6, rel=1e-12)
        caption = fig.legends[0].get_title().get_text()
        assert "wind-up" in caption.replace("-\n", "-") and "mean 140.3 µm" in caption
        te_left = fig.axes[0].get_lines()[0].get_ydata()
        assert abs(te_left.mean()) < 0.05 and np.ptp(te_left) > 10.0  # about the mean, um
        fig.canvas.draw()
        top = next(a for a in fig.axes[0].child_axes if a.get_xlabel() == "time [ms]")
        boxes = [t.get_window_extent() for t in top.get_xticklabels()
                 if t.get_text() and t.get_visible()]
        boxes = [b for b in boxes if fig.axes[0].bbox.x0 - 1 <= b.x0 <= fig.axes[0].bbox.x1]
        assert len(boxes) >= 3
        assert all(a.x1 + 5 < b.x0 for a, b in itertools.pairwise(boxes))
    finally:
        for fig in figures.values():
            plt.close(fig)


def test_figures_of_a_quick_reproduction_are_stamped(tmp_path):
    """``gsb reproduce --quick`` is not steady state: each of its figures says so across it
    and under its title; a full reproduction's do not. Each names the window its steady curves
    are taken over (the plan's, or its own), a transient's none; the plan's window by
    default is the gear revolution, 157 mesh periods (z2 = 157)."""
    from orchestrator.figures.base import pyplot
    from orchestrator.studies.reproduce.figures import _save, _Stamped
    from orchestrator.studies.reproduce.plan import FULL, window_text

    window = window_text(FULL)
    assert window == "last revolution of the slowest shaft gear_shaft, 157 mesh periods"
    for stamp in ("gsb reproduce --quick: trends only", ""):
        for own, shown in ((None, window), ("the last gear revolution", None), ("", "")):
            plt = _Stamped(pyplot(), stamp, window)
            fig, ax = plt.subplots()
            ax.plot([0, 1], [0, 1])
            fig.suptitle("Fig. 0")
            _save(fig, tmp_path / "f.png", plt, own)
            shown = own if shown is None else shown
            assert fig.get_suptitle().split("\n") == (
                ["Fig. 0"] + ([f"window: {shown}"] if shown else []) + ([stamp] if stamp else []))
            across = [t for t in fig.texts if t.get_text() == "gsb reproduce --quick"]
            assert len(across) == bool(stamp)
            assert (tmp_path / "f.png").stat().st_size > 5_000
            plt.close(fig)


def test_gsb_plot_with_another_window(run_file, tmp_path, capsys):
    """``gsb plot FILE --window``: the figures over that window, named on them (the orbits'
    legend, the spectra's notes); a window that is none, or one for a sweep's file, is one
    line naming it."""
    from matplotlib.text import Text

    plt = pyplot()
    figures = make_run_figures(read_results(run_file), "26 periods")
    try:
        texts = {name: " ".join(t.get_text() for t in fig.findobj(Text))
                 for name, fig in figures.items()}
    finally:
        for fig in figures.values():
            plt.close(fig)
    assert "last 26 mesh periods" in texts["orbits.png"]
    assert "last 26 mesh periods" in texts["spectra.png"]
    assert "last revolution of the slowest shaft" not in texts["spectra.png"]
    assert main(["plot", str(run_file), "--window", "26 periods", "--out", str(tmp_path)]) == 0
    assert len(capsys.readouterr().out.split()) == len(RUN_FIGURES)
    assert main(["plot", str(run_file), "--window", "3 kg", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "cannot read '3 kg' as a window" in err and len(err.strip().splitlines()) == 1
