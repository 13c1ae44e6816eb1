"""Sweeps on Dask and the post-processing they rely on."""

import math
import os

import numpy as np
import pytest

from fmu_src.case import load_case
from orchestrator.analysis.metrics import fit_ellipse, steady_window
from orchestrator.sweeps.runner import SweepPoint, read_sweep, read_sweep_attrs, run_sweep

SPUR = "baguet2010_spur"


def test_ellipse_fit_recovers_a_rotated_ellipse_from_a_noisy_orbit():
    rng = np.random.default_rng(0)
    t = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    a, b, phi, c = 3e-5, 1e-5, 0.7, np.array([4e-5, -9e-5])
    x = a * np.cos(t) * math.cos(phi) - b * np.sin(t) * math.sin(phi) + c[0]
    y = a * np.cos(t) * math.sin(phi) + b * np.sin(t) * math.cos(phi) + c[1]
    e = fit_ellipse(x, y)
    np.testing.assert_allclose(e["centre"], c, rtol=1e-10)
    np.testing.assert_allclose(e["axes"], [a, b], rtol=1e-10)
    assert e["angle"] % math.pi == pytest.approx(phi, abs=1e-10)
    # 26 mesh oscillations on the orbit (Fig. 9) barely move the centre
    e2 = fit_ellipse(x + 2e-6 * np.cos(26 * t) + 1e-7 * rng.standard_normal(t.size), y)
    np.testing.assert_allclose(e2["centre"], c, atol=5e-7)
    with pytest.raises(ValueError, match="6 points"):
        fit_ellipse([0, 1], [1, 0])


def test_steady_window():
    t = np.arange(10) * 0.1
    assert steady_window(t, 0.3).tolist() == [False] * 7 + [True] * 3
    assert steady_window(t, 5.0).all()


@pytest.mark.parametrize("scheduler", ["none", None], ids=["serial", "local-cluster"])
def test_sweep_gathers_points_and_reports_a_failed_one(scheduler, tmp_path):
    """Two speeds and a bad point; serial in this process or on a 2-worker LocalCluster. The
    failed point is reported with its reason, the others are kept, in point order; the
    LocalCluster leaves this process's environment as it was (Dask's nanny sets the BLAS
    thread counts of later child processes to 1 there)."""
    import threadpoolctl  # noqa: F401 - its import sets KMP_DUPLICATE_LIB_OK, not the sweep

    environment = dict(os.environ)
    points = [SweepPoint({"drive.speed": 200.0}, "linear", "a"),
              SweepPoint({"drive.speed": -5.0}, "linear", "bad"),
              SweepPoint({"drive.speed": 400.0}, "linear", "b")]
    case = load_case(SPUR, {"simulation.window": "2 periods"})
    res = run_sweep(case, points, tmp_path / "s.h5", periods=4, scheduler=scheduler,
                    progress=False)
    assert [i for i, _ in res.failed] == [1]
    assert "drive.speed" in res.failed[0][1]
    assert dict(os.environ) == environment
    data = read_sweep(res.path)
    assert [d["label"] for d in data] == ["a", "bad", "b"]
    assert [d["values"].tolist() for d in data] == [[200.0], [-5.0], [400.0]]
    a = read_sweep_attrs(res.path)
    assert a["kind"] == "sweep" and a["vary_keys"] == ["drive.speed"]
    assert a["vary_units"] == ["rad/s"] and a["bearings"] == ["linear"]
    assert not a["complete"] and a["status"] == "failed points" and a["n_failed"] == 1
    assert data[1]["error"] and "R" not in data[1]
    for d in (data[0], data[2]):
        assert d["error"] is None
        assert d["R"] > 1.0 and d["force_ptp"].shape == (4,)
        assert d["orbit"].shape[1:] == (4, 2)
        assert d["spectrum"].shape == (4, d["spectrum_orders"].size)
    # labelled: the varied field and the bearing model as dimensions, the failed point NaN
    ds = res.to_xarray()
    assert ds.R.dims == ("drive_speed", "bearing_model", "mesh")
    assert ds.drive_speed.values.tolist() == [-5.0, 200.0, 400.0]
    assert ds.drive_speed.attrs["units"] == "rad/s"
    assert ds.bearing_model.values.tolist() == ["linear"]
    at = ds.sel(bearing_model="linear")
    assert at.R.sel(drive_speed=200.0).values.tolist() == data[0]["R"].tolist()
    assert at.force_ptp.sel(drive_speed=400.0).values.tolist() == data[2]["force_ptp"].tolist()
    assert np.isnan(at.R.sel(drive_speed=-5.0)).all() and not at.ok.sel(drive_speed=-5.0)
    assert "drive.speed" in at.error.sel(drive_speed=-5.0).item()
    assert at.force_ptp.dims == ("drive_speed", "bearing") and ds.bearing.size == 4


def test_a_point_whose_journal_touched_its_bearing_is_told_apart_from_a_solver_failure():
    """A run that ended because a journal reached its clearance circle (the check's own
    EccentricityError, somewhere among the run error's causes) is a physics stop, counted
    apart (gsb sweep, gsb reproduce); a coupled iteration or a solver giving up is not."""
    from bearing_fmu.base import check_state
    from orchestrator.coupling.master import NotConvergedError
    from orchestrator.run.spec import RunError
    from orchestrator.sweeps.runner import _touched, stopped_on_physics

    def run_error(cause):
        try:
            try:
                cause()
            except Exception as exc:
                raise RunError("step 40 of 64 (t = 0.001 s) failed: ...") from exc
        except RunError as exc:
            return exc

    def not_converged():
        raise NotConvergedError("did not converge in 30 iterations")

    touched = run_error(lambda: check_state(0.6, 0.9, 0.0, 0.0))
    assert "the journal touches the bearing" in str(touched.__cause__)
    assert _touched(touched) and not _touched(run_error(not_converged))
    assert stopped_on_physics("stopped on physics (a journal touched its bearing): RunError: x")
    assert not stopped_on_physics("RunError: step 3 failed: did not converge")


def test_a_sweep_from_an_unguarded_script_stops_at_once_with_one_line(tmp_path):
    """A plain script calling ``gsb.sweep`` at its top level, outside ``if __name__ ==
    "__main__":``: the local cluster's worker processes would import it again and start
    sweeps of their own (multiprocessing's bootstrapping error, 255 lines, then "Nanny
    failed to start"). It stops before any process or file, the error naming the script's
    line, the guard and the in-process option."""
    import subprocess
    import sys

    from tests.helpers import probe_env

    script = tmp_path / "plain.py"
    script.write_text("import orchestrator as gsb\n"
                      "gsb.sweep('baguet2010_spur', {'drive.speed': [300, 325]}, 'sweep.h5',\n"
                      "          periods=2, progress=False)\n")
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=300, cwd=tmp_path, env=probe_env())
    last = proc.stderr.strip().splitlines()[-1]
    assert proc.returncode == 1 and "bootstrapping" not in proc.stderr, proc.stderr[-2000:]
    assert last.startswith(f"orchestrator.run.spec.RunError: {script}:2: a sweep on a local "
                           "Dask cluster starts worker processes"), last
    assert '`if __name__ == "__main__":`' in last and 'scheduler="none"' in last
    assert not (tmp_path / "sweep.h5").exists()


def test_a_sweep_that_is_not_a_grid_is_labelled_by_point(tmp_path):
    """Points that do not fill the product of their values (a run_sweep of chosen points):
    one dimension ``point``, the varied values and the model as coordinates along it."""
    from orchestrator.sweeps import file as sweep_file

    case = load_case(SPUR)
    path = tmp_path / "s.h5"
    keys = ["drive.speed", "drive.torque"]
    sweep_file.write_header(path, case, keys, ["linear"], 4, "last 2 mesh periods", 2)
    points = [SweepPoint({"drive.speed": 200.0, "drive.torque": 100.0}, "linear"),
              SweepPoint({"drive.speed": 300.0, "drive.torque": 150.0}, "linear")]
    for i, pt in enumerate(points):
        data = {"R": np.array([1.0 + i]), "force_ptp": np.full(4, 10.0 * i)}
        sweep_file.store_point(path, i, pt, case, keys, {"ok": True, "data": data}, 0)
    ds = sweep_file.sweep_dataset(path)
    assert ds.R.dims == ("point", "mesh")
    assert ds.drive_speed.values.tolist() == [200.0, 300.0]
    assert ds.drive_torque.values.tolist() == [100.0, 150.0]
    assert ds.R.values.ravel().tolist() == [1.0, 2.0]
    assert np.isnan(ds.orbit_centre).all()  # not stored: NaN, not an error


def test_the_api_never_overwrites_a_sweep_file_silently(tmp_path):
    import orchestrator as gsb
    from orchestrator.run.spec import RunError

    path = tmp_path / "s.h5"
    path.write_text("a file of the user's")
    with pytest.raises(RunError, match="exists: a sweep never replaces a file silently"):
        gsb.sweep(SPUR, {"drive.speed": [200.0]}, path, periods=4, scheduler="none")
    assert path.read_text() == "a file of the user's"
    with pytest.raises(ValueError, match="not a readable sweep file"):
        gsb.read_sweep(path)
    with pytest.raises(FileNotFoundError, match="no such sweep file"):
        gsb.read_sweep(tmp_path / "none.h5")


def test_a_sweeps_window_in_revolutions_follows_each_points_speed(tmp_path):
    """``gsb.sweep(window="1 revolution of pinion_shaft")`` at two speeds: each point is
    reduced over one pinion revolution at its own speed, 2 pi / w (closed form), stored as
    ``window_s`` with the window's name as the file's attribute and in the xarray dataset;
    the stored steady samples span it. A window longer than a point's run is a CaseError
    naming the point before anything runs; ``steady_periods`` is the earlier spelling of
    ``window="N periods"`` and warns."""
    import warnings

    import orchestrator as gsb
    from fmu_src.case import CaseError

    speeds = [200.0, 400.0]
    res = gsb.sweep(SPUR, {"drive.speed": speeds}, tmp_path / "s.h5", periods=30,
                    bearings=["linear"], window="1 revolution of pinion_shaft",
                    scheduler="none", progress=False)
    assert res.complete, res.failed
    ds = res.to_xarray()
    assert ds.attrs["window"] == "last 1 revolution of pinion_shaft"
    window = ds.window_s.sel(bearing_model="linear").values
    np.testing.assert_allclose(window, [2 * math.pi / w for w in speeds], rtol=1e-12)
    for point, w in zip(read_sweep(res.path), window, strict=True):
        dt = point["time"][1] - point["time"][0]
        assert point["time"][-1] - point["time"][0] == pytest.approx(w - dt, rel=1e-9)
    with pytest.raises(CaseError, match=r"point 1 .*longer than the run"):
        gsb.sweep(SPUR, {"drive.speed": [100.0, 1000.0]}, tmp_path / "t.h5", periods=30,
                  window="0.05 s", scheduler="none", progress=False)
    assert not (tmp_path / "t.h5").exists()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = gsb.sweep(SPUR, {"drive.speed": [300.0]}, tmp_path / "u.h5", periods=4,
                        bearings=["linear"], steady_periods=3, scheduler="none",
                        progress=False)
    assert [w.category for w in caught] == [DeprecationWarning]
    assert "window='3 periods'" in str(caught[0].message)
    assert read_sweep_attrs(res.path)["window"] == "last 3 mesh periods"
