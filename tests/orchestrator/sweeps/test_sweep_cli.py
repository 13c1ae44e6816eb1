"""``gsb sweep``: a Dask scheduler and worker of their own (other folders than the client's),
a lost worker, Ctrl-C, bad inputs, the units of the sweep file, the order spectrum and the
figures. Tiny runs: 2 mesh periods of 16 steps, linear bearings."""

from __future__ import annotations

import json
import math
import os
import shutil
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import h5py
import numpy as np
import pytest

from fmu_src.case import load_case, parse_case, shipped_cases
from orchestrator.analysis.spectrum import PAD
from orchestrator.cli import main
from orchestrator.sweeps.runner import DATASETS, point_spectrum, read_sweep_attrs

SPUR = "baguet2010_spur"
TINY = ["--periods", "2", "--set", "simulation.steps_per_mesh_period=16", "--bearing", "linear"]
DASK = Path(sys.executable).with_name("dask")


def _gsb(args, cwd, timeout=120, **kw):
    return subprocess.run([sys.executable, "-m", "orchestrator.cli", "sweep", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=timeout, **kw)


def _stop(*procs):
    for p in procs:
        if p is not None and p.poll() is None:
            p.terminate()
    for p in procs:
        if p is not None:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


def _scheduler(folder: Path):
    """A Dask scheduler in its own folder; (process, address)."""
    folder.mkdir(parents=True, exist_ok=True)
    info = folder / "scheduler.json"
    proc = subprocess.Popen([str(DASK), "scheduler", "--host", "127.0.0.1", "--port", "0",
                             "--no-dashboard", "--dashboard-address", ":0",
                             "--scheduler-file", str(info)], cwd=folder,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    t0 = time.monotonic()
    while not info.is_file() or not info.read_text().strip():
        if proc.poll() is not None or time.monotonic() - t0 > 60:
            _stop(proc)
            pytest.fail("the Dask scheduler did not start")
        time.sleep(0.2)
    return proc, json.loads(info.read_text())["address"]


@pytest.fixture(scope="module")
def dask_sweep(tmp_path_factory):
    """``gsb sweep`` run from a client folder on a case file given by a relative path, on a
    scheduler and one worker started elsewhere (the worker's folder has no case file)."""
    root = tmp_path_factory.mktemp("dask")
    client, worker_dir = root / "client", root / "worker"
    client.mkdir()
    worker_dir.mkdir()
    shutil.copy(shipped_cases()[SPUR], client / "my_case.toml")
    sched = worker = None
    try:
        sched, address = _scheduler(root / "scheduler")
        worker = subprocess.Popen([str(DASK), "worker", address, "--nthreads", "1",
                                   "--no-nanny", "--no-dashboard"], cwd=worker_dir,
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        t0 = time.monotonic()
        res = _gsb(["my_case.toml", "--vary", "speed=3000,4500 rpm", *TINY, "--scheduler",
                    address, "--out", "out", "--no-figures", "--quiet"], client)
        wall = time.monotonic() - t0
    finally:
        _stop(worker, sched)
    files = list((client / "out").glob("*.h5"))
    return res, files, wall, client


def test_dask_sweep_sends_the_case_content_to_a_worker_elsewhere(dask_sweep):
    res, files, wall, _ = dask_sweep
    print(f"\nDask sweep of 2 points on a scheduler + 1 worker: {wall:.1f} s")
    assert res.returncode == 0, res.stderr
    assert "Traceback" not in res.stderr
    assert len(files) == 1
    assert files[0].name.startswith(f"{SPUR}_sweep_") and len(files[0].stem) == len(SPUR) + 15
    assert str(files[0].relative_to(files[0].parents[1])) in res.stdout
    with h5py.File(files[0]) as f:
        assert bool(f.attrs["complete"]) and f.attrs["status"] == "complete"
        assert f.attrs["n_failed"] == 0 and len(f["points"]) == 2
        for g in f["points"].values():
            assert "error" not in g.attrs
            for name, d in g.items():
                assert d.attrs["unit"] == DATASETS[name][0] and d.attrs["description"], name


def test_sweep_file_attributes_units_and_values(dask_sweep):
    """Root attributes numeric (not JSON), the effective case reloads bit for bit, ``values``
    are the speeds in rad/s; the spectrum's order-0 bin is the mean force over its window."""
    _, files, _, client = dask_sweep
    a = read_sweep_attrs(files[0])
    assert a["kind"] == "sweep" and a["case"] == SPUR
    assert a["vary_keys"] == ["drive.speed"] and a["vary_units"] == ["rad/s"]
    assert a["bearings"] == ["linear"]
    assert (a["periods"], a["window"]) == (2, "last half of the run")
    assert a["wall_time"] > 0
    expected = load_case(client / "my_case.toml", {"simulation.steps_per_mesh_period": 16})
    assert parse_case(tomllib.loads(a["case_toml"])).values == expected.values
    with h5py.File(files[0]) as f:
        speeds = [f["points"][k].attrs["values"][0] for k in sorted(f["points"])]
        np.testing.assert_allclose(speeds, [3000 * math.pi / 30, 4500 * math.pi / 30],
                                   rtol=1e-15)
        for g in f["points"].values():
            assert g.attrs["bearing"] == "linear"
            assert json.loads(g.attrs["overrides"]) == {"drive.speed": g.attrs["values"][0]}
            orders, spec = g["spectrum_orders"][()], g["spectrum"][()]
            z1 = 26
            assert spec.shape == (4, orders.size) and orders[-1] <= 3.5 * z1
            # one mesh period: a resolution of z1, zero-padded PAD times
            np.testing.assert_allclose(np.diff(orders), z1 / PAD)
            # the window is the steady window (one mesh period < one revolution): order 0 is
            # the mean of ||F_b|| over it
            np.testing.assert_allclose(spec[:, 0], g["force_mean"][()], rtol=1e-12)
            assert g["R"][()] > 1.0


def test_order_spectrum_of_a_synthetic_force_recovers_its_lines():
    """Known lines at orders 1, 2.5, z1, 2 z1, 3 z1 (pinion revolutions) in ||F_b||: the
    spectrum over the last whole revolutions of the steady window reads them exactly at their
    orders (on bins: orchestrator.analysis.spectrum.order_spectrum), and the mean at order 0;
    the samples before the window (a large transient) are left out."""
    case = load_case(SPUR, {"simulation.steps_per_mesh_period": 16})
    z1, per_mesh = 26, 16
    n = 60 * per_mesh  # 60 mesh periods simulated
    dt = 2 * math.pi / (case["drive.speed"] * z1) / per_mesh
    t = (np.arange(n) + 1) * dt
    theta = t * case["drive.speed"] / (2 * math.pi)  # pinion revolutions
    lines = {1.0: 40.0, 2.5: 4.0, 26.0: 25.0, 52.0: 7.0, 78.0: 3.0}
    norm = 500.0 + sum(a * np.cos(2 * np.pi * q * theta + q) for q, a in lines.items())
    norm[: n - 2 * z1 * per_mesh] += 1e4  # not in the window: 2 revolutions
    scale = np.array([1.0, 2.0, 3.0, 4.0])
    phi = 0.3 * t[:, None] / dt  # the force direction turns: only its norm counts
    force = np.stack([norm[:, None] * scale * np.cos(phi), norm[:, None] * scale * np.sin(phi)],
                     axis=-1)
    out = point_spectrum(case, {"time": t, "bearing_force": force}, window_s=57 * per_mesh * dt)
    orders, spec = out["spectrum_orders"], out["spectrum"]
    step = 0.5 / PAD  # two revolutions, zero-padded PAD times
    np.testing.assert_allclose(orders, np.arange(orders.size) * step, rtol=1e-12, atol=0)
    assert orders[-1] == pytest.approx(3.5 * z1, rel=1e-12)
    for q, a in {0.0: 500.0, **lines}.items():
        k = round(q / step)
        np.testing.assert_allclose(spec[:, k] / scale, a, rtol=0, atol=1e-9, err_msg=f"order {q}")
    np.testing.assert_allclose(out["spectrum_window"], [t[n - 2 * z1 * per_mesh - 1], t[-1]])


def test_a_worker_takes_the_case_content_never_a_path():
    """What a worker runs: a Case or its TOML text (reloaded bit for bit); a path, which would
    name the client's folders, is refused as the point's error."""
    from orchestrator.sweeps.runner import SweepPoint, as_case, run_point

    case = load_case(SPUR, {"simulation.steps_per_mesh_period": 16})
    assert as_case(case.to_toml()).values == case.values
    point = SweepPoint({"drive.speed": 400.0}, "linear")
    res = run_point(case.to_toml(), point, 2, 1)
    # one mesh period (z1 orders) zero-padded PAD times, orders 0 to 3.5 z1
    assert res["ok"] and res["data"]["spectrum"].shape == (4, math.floor(3.5 * PAD) + 1)
    res = run_point(str(shipped_cases()[SPUR]), point, 2, 1)
    assert not res["ok"] and "TOML text" in res["error"]


@pytest.fixture(scope="module")
def empty_scheduler(tmp_path_factory):
    root = tmp_path_factory.mktemp("empty")
    proc, address = _scheduler(root / "scheduler")
    try:
        yield address
    finally:
        _stop(proc)


def test_no_worker_stops_after_the_worker_timeout(empty_scheduler, tmp_path):
    t0 = time.monotonic()
    res = _gsb([SPUR, "--vary", "speed=300,400", *TINY, "--scheduler", empty_scheduler,
                "--worker-timeout", "2", "--out", "out", "--quiet"], tmp_path, timeout=60)
    wall = time.monotonic() - t0
    print(f"\nno worker, --worker-timeout 2: exit {res.returncode} after {wall:.1f} s; "
          f"{res.stderr.strip()}")
    assert res.returncode == 1
    assert wall < 30
    assert "Traceback" not in res.stderr
    assert "worker timeout" in res.stderr and "--worker-timeout 2" in res.stderr
    (path,) = (tmp_path / "out").glob("*.h5")
    assert str(path.relative_to(tmp_path)) in res.stderr
    with h5py.File(path) as f:
        assert not f.attrs["complete"] and f.attrs["status"] == "worker timeout"
        assert f.attrs["n_failed"] == 2
        for g in f["points"].values():
            assert "no Dask worker connected" in g.attrs["error"]


def test_ctrl_c_keeps_the_file_marked_incomplete(empty_scheduler, tmp_path):
    proc = subprocess.Popen([sys.executable, "-m", "orchestrator.cli", "sweep", SPUR, "--vary",
                             "speed=300,400", *TINY, "--scheduler", empty_scheduler, "--out",
                             "out"], cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        t0 = time.monotonic()
        while not list((tmp_path / "out").glob("*.h5")) and time.monotonic() - t0 < 60:
            time.sleep(0.2)
        time.sleep(1.0)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        _stop(proc)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "interrupted" in err
    (path,) = (tmp_path / "out").glob("*.h5")
    with h5py.File(path) as f:
        assert not f.attrs["complete"] and f.attrs["status"] == "interrupted"


BAD = {
    "unknown key": (["--vary", "spin=1,2"], ["--vary spin=1,2", "unknown key 'spin'"]),
    "malformed": (["--vary", "speed=100:200"], ["--vary speed=100:200", "START:STOP:COUNT"]),
    "count 0": (["--vary", "speed=100:200:0"], ["--vary speed=100:200:0", "COUNT 0", ">= 1"]),
    "count not int": (["--vary", "speed=100:200:2.5"], ["'2.5'", "not an integer"]),
    "not a number": (["--vary", "speed=100,abc"], ["--vary speed=100,abc", "'abc'"]),
    "unit": (["--vary", "speed=100,200 furlongs"], ["--vary speed=100,200 furlongs",
                                                    "furlongs"]),
    "not numeric": (["--vary", "simulation.damping_model=1,2"], ["choice field"]),
    "too many": (["--vary", "speed=100:1200:101", "--vary", "torque=50:600:100"],
                 ["10100 points", "<= 10000"]),
    "twice": (["--vary", "speed=100,200", "--vary", "drive.speed=1,2"], ["varied twice"]),
    "bearing": (["--vary", "speed=100,200", "--bearing", "hybrid,magic"],
                ["--bearing hybrid,magic", "'magic'", "lumped"]),
    "periods": (["--vary", "speed=100,200", "--periods", "0"], ["--periods 0", ">= 1"]),
    "window": (["--vary", "speed=100,200", "--periods", "2", "--window", "5 periods"],
               ["--window '5 periods' for --periods 2", "point 0", "longer than the run"]),
    "window in s": (["--vary", "speed=100,200", "--periods", "64", "--window", "1 s"],
                    ["--window '1 s' for --periods 64", "point 0 (", "longer than the run"]),
    "window text": (["--vary", "speed=100,200", "--window", "5 furlongs"],
                    ["simulation.window", "'5 furlongs'", "'26 periods'"]),
    "window shaft": (["--vary", "speed=100,200", "--window", "2 revolutions of rotor"],
                     ["rotor"]),
    "window twice": (["--vary", "speed=100,200", "--window", "5 periods",
                      "--steady-periods", "5"], ["--steady-periods 5", "not both"]),
    "steady": (["--vary", "speed=100,200", "--periods", "2", "--steady-periods", "5"],
               ["--window '5 periods' for --periods 2", "longer than the run"]),
    "timeout": (["--vary", "speed=100,200", "--worker-timeout", "0"],
                ["--worker-timeout 0", "> 0"]),
    "workers": (["--vary", "speed=100,200", "--workers", "0"], ["--workers 0", ">= 1"]),
    "rejected value": (["--vary", "speed=-100,200"],
                       ["--vary speed=-100,200", "drive.speed = -100.0", "> 0.0 rad/s"]),
    "rejected point": (["--set", "bearings.*.model=fd", "--vary", "bearings.*.nodes=8,32",
                        "--bearing", "fd,hybrid"],
                       ["point 2 (hybrid, nodes 8)", "bearings.1.nodes = 8", ">= 16"]),
    "set": (["--vary", "speed=100,200", "--set", "drive.torque=-3"],
            ["drive.torque", "-3"]),
    "case": (["--vary", "speed=100,200"], ["case file not found", "no_such_case"]),
}


@pytest.mark.parametrize("args,expected", BAD.values(), ids=BAD.keys())
def test_bad_input_is_one_line_and_exit_2(args, expected, capsys, tmp_path):
    case = "no_such_case" if "no_such_case" in expected else SPUR
    code = main(["sweep", case, *args, "--out", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.startswith("gsb sweep: error: ") and err.count("\n") == 1, err
    assert "Traceback" not in err
    for text in expected:
        assert text in err, (text, err)
    assert not list(tmp_path.iterdir())  # nothing started, nothing written


def test_serial_sweep_refuses_to_overwrite_without_the_option(capsys, tmp_path):
    args = ["sweep", SPUR, "--vary", "speed=300", *TINY, "--scheduler", "none", "--out",
            str(tmp_path), "--no-figures", "--quiet"]
    assert main(args) == 0
    (path,) = tmp_path.glob("*.h5")
    assert f"sweep: {path}" in capsys.readouterr().out
    assert main(args) == 2
    err = capsys.readouterr().err
    assert str(path) in err and "--overwrite" in err and err.count("\n") == 1
    assert main([*args, "--overwrite"]) == 0
    with h5py.File(path) as f:
        assert f.attrs["complete"] and f.attrs["n_points"] == 1


def test_sweep_figures_of_a_two_speed_sweep(dask_sweep, tmp_path, monkeypatch):
    """R / peak-to-peak and a waterfall per shaft (its first bearing, in orders of that
    shaft), titled with the case, the bearing model and the fixed operating values, axes
    labelled with units."""
    from orchestrator.figures import sweep as sf

    _, files, _, _ = dask_sweep
    seen = {}
    save = sf._save

    def spy(fig, path, plt):
        seen[path.name] = (fig.get_suptitle(), [(ax.get_xlabel(), ax.get_ylabel())
                                               for ax in fig.axes if ax.get_visible()])
        return save(fig, path, plt)

    monkeypatch.setattr(sf, "_save", spy)
    paths = sf.sweep_figures(files[0], tmp_path / "figs")
    assert [p.name for p in paths] == ["R_ptp.png", "waterfall_bearing1.png",
                                       "waterfall_bearing3.png"]
    assert all(p.is_file() and p.stat().st_size > 10_000 for p in paths)
    for title, labels in seen.values():
        assert SPUR in title and "linear" in title and "torque 220 N m" in title
        assert "unbalance 0.6 mm (every gear)" in title
        assert "speed" not in title.split(";")[1]
        assert ("input speed [rad/s]", "peak-to-peak ||F_b|| [N]") in labels or \
            ("order [1/pinion_shaft rev]", "input speed [rad/s]") in labels or \
            ("order [1/gear_shaft rev]", "input speed [rad/s]") in labels
    # the waterfall's colour scale: the peak amplitude of every spectrum, in N
    assert ("", "bearing 1: ||F_b|| amplitude [N] (peak)") in seen["waterfall_bearing1.png"][1]
    assert ("order [1/gear_shaft rev]", "input speed [rad/s]") in \
        seen["waterfall_bearing3.png"][1]
    # default folder: beside the file, named after its stem
    default = sf.sweep_figures(files[0])
    assert default[0].parent == files[0].with_suffix("")
    if os.environ.get("GSB_KEEP_FIGURES"):
        print("\n" + "\n".join(str(p) for p in default))


def test_a_run_ups_sweep_spectrum_is_in_orders_of_its_final_speed():
    """A sweep point of a run-up (325 -> 400 rad/s in 1 ms) whose window lies at the final
    speed: the stored spectrum reads the synthetic lines at their orders of 400 rad/s, as at a
    constant 400 rad/s (whole revolutions of it in the window: exact to round-off, 1e-9)."""
    case = load_case(SPUR, {"simulation.steps_per_mesh_period": 16,
                            "drive.speed_profile": "ramp to 400 rad/s in 1 ms"})
    z1, per_mesh, w = 26, 16, 400.0
    dt = 2 * math.pi / (w * z1) / per_mesh
    n = 60 * per_mesh
    t = (np.arange(n) + 1) * dt
    theta = t * w / (2 * math.pi)  # pinion revolutions (a constant offset: phases only)
    lines = {1.0: 40.0, 26.0: 25.0}
    norm = 500.0 + sum(a * np.cos(2 * np.pi * q * theta + q) for q, a in lines.items())
    force = np.stack([norm[:, None] * np.ones(4), np.zeros((n, 4))], axis=-1)
    out = point_spectrum(case, {"time": t, "bearing_force": force}, window_s=57 * per_mesh * dt)
    orders, spec = out["spectrum_orders"], out["spectrum"]
    for q, a in lines.items():
        k = int(np.argmin(np.abs(orders - q)))
        assert orders[k] == pytest.approx(q, rel=1e-12)
        np.testing.assert_allclose(spec[:, k], a, rtol=1e-9, err_msg=f"order {q}")
