"""What a run, a sweep and a modal analysis give for a train beyond the paper's pair: the
shipped two-stage reducer (3 shafts, meshes stage1 and stage2, 6 bearings, hybrid and short),
in-process, through the command line in this process.

Every name the user sees is the case's: the results file's dimensions (bearing, mesh, gear),
the report (R per mesh, peak-to-peak per bearing), the figures' panels, the sweep's datasets
and the modal analysis's critical speeds per mesh.
"""

import contextlib
import io
import re
from pathlib import Path

import numpy as np
import pytest

from fmu_src import description
from fmu_src.case import load_case
from fmu_src.description import layout, mesh_period
from orchestrator.cli import main
from orchestrator.run.results import read_results

CASE = "two_stage_reducer"
BEARINGS = ["in_a", "in_b", "mid_a", "mid_b", "out_a", "out_b"]
MESHES = ["stage1", "stage2"]
GEARS = ["pinion1", "wheel1", "pinion2", "wheel2"]


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """``gsb run two_stage_reducer --in-process --periods 8``: (stdout, results file)."""
    out = tmp_path_factory.mktemp("two_stage")
    stdout = io.StringIO()
    with contextlib.redirect_stdout(stdout):
        code = main(["run", CASE, "--in-process", "--periods", "8", "--quiet", "--out",
                     str(out)])
    text = stdout.getvalue()
    assert code == 0, text
    return text, Path(re.search(r"^results: (.*)$", text, re.MULTILINE).group(1))


def test_results_file_is_labelled_by_the_train_names(run):
    """xarray opens the file with the bearings, meshes and gears by name; a labelled
    selection is the raw array's component."""
    import xarray as xr

    _, path = run
    raw = read_results(path)
    assert raw["time"].shape == (256,)
    with xr.open_dataset(path, engine="h5netcdf") as ds:
        assert dict(ds.sizes) == {"time": 256, "bearing": 6, "axis": 2, "mesh": 2, "gear": 4,
                                  "shaft": 3}
        assert list(ds.bearing.values) == BEARINGS
        assert list(ds.mesh.values) == MESHES
        assert list(ds.gear.values) == GEARS
        assert ds.mesh_force.dims == ("time", "mesh")
        assert ds.gear_node.dims == ("time", "gear", "axis")
        assert np.array_equal(ds.bearing_force.sel(bearing="mid_b", axis="s").values,
                              raw["bearing_force"][:, 3, 0])
        assert np.array_equal(ds.transmission_error.sel(mesh="stage2").values,
                              raw["transmission_error"][:, 1])
    a = raw["attrs"]
    assert [str(s) for s in a["bearing_shafts"]] == ["input"] * 2 + ["intermediate"] * 2 + \
        ["output"] * 2
    assert np.asarray(a["mesh_teeth"]).tolist() == [[23, 79], [21, 73]]


def test_report_per_mesh_and_per_bearing(run):
    """R and the TE peak-to-peak per mesh, the force peak-to-peak per bearing, in the
    summary and the file, equal to what the channels give over the window (the last half of
    an 8-period run: far shorter than a revolution of the output shaft); every line in the
    orders of each bearing's own shaft."""
    text, path = run
    r = read_results(path)
    a = r["attrs"]
    assert str(a["report_window_kind"]) == "last half of the run"
    win = slice(128, None)
    case = load_case(CASE)
    lay = layout(case)
    from orchestrator.analysis.metrics import static_mesh_loads

    w0 = static_mesh_loads(case)
    # the static loads: each driver's shaft torque (200 N m in, x 79/23 on the intermediate
    # shaft) over the driver's base radius and cos(beta_b) (helical stage 1, spur stage 2)
    pairs = description.gear_pairs(case)
    np.testing.assert_allclose(w0, [200.0 / (pairs[0].base_radius[0]
                                             * np.cos(pairs[0].base_helix_angle)),
                                    200.0 * 79 / 23 / pairs[1].base_radius[0]], rtol=1e-12)
    assert pairs[1].base_helix_angle == 0.0
    np.testing.assert_array_equal(a["dynamic_factor"], r["mesh_force"][win].max(axis=0) / w0)
    np.testing.assert_array_equal(a["transmission_error_ptp"],
                                  np.ptp(r["transmission_error"][win], axis=0))
    norm = np.hypot(r["bearing_force"][win, :, 0], r["bearing_force"][win, :, 1])
    np.testing.assert_array_equal(a["bearing_force_ptp"], np.ptp(norm, axis=0))
    assert a["dynamic_factor"].shape == (2,) and a["bearing_force_ptp"].shape == (6,)
    assert (a["dynamic_factor"] > 1.0).all()
    labels = [str(x) for x in a["line_labels"]]
    assert labels == ["input_1x", "intermediate_1x", "output_1x", "stage1_GMF", "stage1_2GMF",
                      "stage1_3GMF", "stage2_GMF", "stage2_2GMF", "stage2_3GMF"]
    orders = np.asarray(a["line_orders"])
    assert orders.shape == (6, 9)
    # stage 1 meshes 23 times per input revolution, 79 per intermediate one; stage 2 21 times
    # per intermediate revolution and 73 per output one
    assert orders[0, 3] == pytest.approx(23) and orders[2, 3] == pytest.approx(79)
    assert orders[3, 6] == pytest.approx(21) and orders[5, 6] == pytest.approx(73)
    assert orders[4, 2] == pytest.approx(1) and orders[0, 0] == 1.0
    ratio = float(lay.ratios[2])
    np.testing.assert_allclose(a["line_frequencies"][2], 3000 / 60 * ratio, rtol=1e-12)
    # the printed report names the meshes and the bearings
    assert (f"stage1: R = {a['dynamic_factor'][0]:.3f}" in text
            and f"stage2: R = {a['dynamic_factor'][1]:.3f}" in text)
    assert "bearing force peak-to-peak [N]: in_a: " in text and "out_b: " in text
    head = next(line for line in text.splitlines() if line.split()[:3] == ["line", "f", "[Hz]"])
    assert head.split()[3:] == BEARINGS
    assert "bearings out_a, out_b: input_1x 11.94, intermediate_1x 3.476, output_1x 1" in text
    assert re.search(r"^bearing mid_a: s/C = ", text, re.MULTILINE)


def test_figures_are_written_with_a_panel_per_bearing_shaft_and_mesh(run):
    """The four figures beside the file; the orbits a panel per bearing (titled by name and
    shaft), the spectra a panel per shaft in its orders, the mesh figure two rows per mesh."""
    from orchestrator.figures.base import pyplot
    from orchestrator.figures.run import RUN_FIGURES, make_run_figures

    text, path = run
    figures = [Path(p) for p in re.findall(r"^figure: (.*)$", text, re.MULTILINE)]
    assert [p.name for p in figures] == list(RUN_FIGURES)
    assert all(p.is_file() and p.stat().st_size > 20_000 for p in figures)
    plt = pyplot()
    drawn = make_run_figures(read_results(path))
    try:
        titles = [ax.get_title() for ax in drawn["orbits.png"].axes if ax.get_title()]
        assert [t.split(",")[0] for t in titles] == [
            "bearing in_a (shaft input)", "bearing in_b (shaft input)",
            "bearing mid_a (shaft intermediate)", "bearing mid_b (shaft intermediate)",
            "bearing out_a (shaft output)", "bearing out_b (shaft output)"]
        spectra = [ax for ax in drawn["spectra.png"].axes if ax.get_ylabel()]
        assert [ax.get_xlabel().split(" (")[0] for ax in spectra] == [
            "order [1/input rev]", "order [1/intermediate rev]", "order [1/output rev]"]
        labels = [ax.get_ylabel() for ax in drawn["mesh.png"].axes if ax.get_ylabel()]
        assert "TE - mean (stage1) [µm]" in labels and "W - W0 (stage2) [N]" in labels
        forces = drawn["bearing_forces.png"].axes
        assert sum(ax.get_legend() is not None for ax in forces) == 3  # a panel per shaft
    finally:
        for fig in drawn.values():
            plt.close(fig)


def test_a_speed_sweep_of_the_two_stage_reducer(tmp_path, capsys):
    """``gsb sweep two_stage_reducer --vary speed=2800,3000 rpm`` in this process, 4 periods
    per point: R per mesh and the peak-to-peak per bearing stored per point, the names as
    the file's attributes, and the figures: R_ptp and a waterfall per shaft."""
    from orchestrator.sweeps.file import read_sweep, read_sweep_attrs

    code = main(["sweep", CASE, "--vary", "speed=2800,3000 rpm", "--periods", "4",
                 "--scheduler", "none", "--quiet", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0, out
    path = Path(re.search(r"^sweep: (.*)$", out, re.MULTILINE).group(1))
    attrs = read_sweep_attrs(path)
    assert attrs["bearing_names"] == BEARINGS and attrs["mesh_names"] == MESHES
    assert attrs["window"] == "last half of the run"  # shorter than an output revolution
    points = read_sweep(path)
    half = 2 * mesh_period(load_case(CASE, {"drive.speed": "2800 rpm"}))
    np.testing.assert_allclose(points[0]["window_s"], half, rtol=1e-12)
    np.testing.assert_allclose(points[0]["time"][-1] - points[0]["time"][0],
                               half - (points[0]["time"][1] - points[0]["time"][0]), rtol=1e-9)
    assert len(points) == 2 and all(p["error"] is None for p in points)
    for p in points:
        assert p["R"].shape == (2,) and (p["R"] > 1.0).all()
        assert p["force_ptp"].shape == (6,) and p["spectrum"].shape[0] == 6
        assert p["mesh_force"].shape[1] == 2
    np.testing.assert_allclose([p["values"][0] for p in points],
                               [2800 * np.pi / 30, 3000 * np.pi / 30], rtol=1e-12)
    figures = sorted(Path(p).name for p in re.findall(r"^figure: (.*)$", out, re.MULTILINE))
    assert figures == ["R_ptp.png", "waterfall_bearing_in_a.png",
                       "waterfall_bearing_mid_a.png", "waterfall_bearing_out_a.png"]


def test_gsb_modal_prints_modes_and_critical_speeds_per_mesh(capsys):
    """``gsb modal two_stage_reducer``: the mean stiffness of each mesh, the damped modes, and
    critical speeds of both meshes, each at its own harmonic of the input speed: k z r omega
    / 2 pi = f_d (r of stage 2: 23/79)."""
    import json

    assert main(["modal", CASE, "--modes", "8"]) == 0
    text = capsys.readouterr().out
    assert "  stage1: " in text and "  stage2: " in text and "N/(mm um)" in text
    assert "f_d [Hz]  zeta [-]  mesh [-]  whirl     type" in text
    assert "mesh name" in text and "stage1: z = 23; stage2: z = 21, r = 0.2911" in text
    assert main(["modal", CASE, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [m["mesh"] for m in out["meshes"]] == MESHES
    rows = out["critical_speeds"]
    assert {r["mesh"] for r in rows} == set(MESHES)
    teeth = {"stage1": (23, 1.0), "stage2": (21, 23 / 79)}
    for r in rows:
        z, ratio = teeth[r["mesh"]]
        assert r["order"] == pytest.approx(r["harmonic"] * z * ratio, rel=1e-12)
        assert 2 * np.pi * r["frequency_hz"] / r["order"] == pytest.approx(r["speed_rad_s"],
                                                                          rel=1e-12)
        mode = out["damped_modes"][r["mode"] - 1]
        assert mode["mesh_shares"][r["mesh"]] >= 0.1
        assert sum(mode["mesh_shares"].values()) == pytest.approx(
            mode["mesh_energy_fraction"], rel=1e-9)


@pytest.mark.parametrize(("argv", "words"), [
    (["--set", "meshes.stage2.centre_distance=300 mm"], ["meshes.stage2", "centre_distance"]),
    (["--torque", "20000 N m"], ["no static solution: bearing in_a carries",
                                 "its film at most", "(shaft input at 314.2 rad/s)",
                                 "bearing out_b carries", "lower drive.torque"]),
])
def test_a_run_time_input_error_is_one_line_and_exit_2(tmp_path, capsys, argv, words):
    """A case the loader refuses, and a torque no static solution can carry (the static loads
    on the films beyond what they carry where the first guess of X0 stops): exit 2, one line
    on stderr naming the mesh, or each bearing and its shaft by name, no traceback."""
    code = main(["run", CASE, "--in-process", "--periods", "2", "--no-figures", "--quiet",
                 *argv, "--out", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("gsb run: error: "), err
    assert "Traceback" not in err
    for word in words:
        assert word in lines[0], lines[0]
