"""The Python API behaves as a library (issue 47 item 4): the command line's settings, a run
length in seconds, labelled results identical in memory and on file, what a first call
compiles said, the Campbell diagram as data."""

import logging
import math

import numpy as np
import pytest
import xarray as xr

import orchestrator as gsb
from fmu_src.case import CaseError
from fmu_src.description import mesh_period

SPUR = "baguet2010_spur"
QUICK = {"in_process": True, "progress": False, "bearing": "linear", "steps": 3}


def test_a_run_in_memory_is_the_dataset_xarray_opens_from_its_file(tmp_path):
    """The same run kept in memory and written to a file: ``to_xarray()`` against
    ``xarray.open_dataset(file)``, identical (dimensions, coordinates, units, every setting
    and figure of the report) but for the wall time, which two runs never share."""
    mem = gsb.simulate(SPUR, periods=1, **QUICK).to_xarray()
    gsb.simulate(SPUR, periods=1, results_dir=tmp_path, **QUICK)
    (path,) = tmp_path.glob("*.h5")
    with xr.open_dataset(path, engine="h5netcdf") as on_file:
        on_file = on_file.load()
    for ds in (mem, on_file):
        del ds.attrs["wall_time"]
    xr.testing.assert_identical(mem, on_file)
    assert mem.attrs["static_journal"].shape == (4, 2)  # arrays keep their shape
    assert isinstance(mem.attrs["complete"], np.bool_)


def test_simulate_takes_the_command_lines_settings_and_seconds():
    r = gsb.simulate(SPUR, speed="400 rad/s", torque=300.0, unbalance="0.3 mm",
                     overrides={"bearings.3.clearance": "120 um"}, seconds=0.004, **QUICK)
    case = gsb.load_case(SPUR, {"drive.speed": 400.0})
    assert r.attrs["speed"] == 400.0 and r.attrs["torque"] == 300.0
    assert list(r.attrs["unbalance"]) == [3e-4, 3e-4]
    assert r.attrs["clearance"][2] == pytest.approx(120e-6, rel=1e-12)
    assert r.attrs["mesh_periods"] == math.ceil(0.004 / mesh_period(case))


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"periods": 4, "seconds": 0.01}, "give one run length"),
    ({"seconds": -1.0}, "seconds = -1.0: the run length must be a finite time > 0 s"),
    ({"speed": "300 kg"}, "drive.speed"),
])
def test_simulate_refuses_bad_settings_by_name(kwargs, message):
    with pytest.raises(CaseError, match=message):
        gsb.simulate(SPUR, **(QUICK | kwargs))


def test_the_first_call_says_what_it_compiles_unless_told_not_to(capsys, monkeypatch):
    """The library logs what a first call builds or compiles on ``gsb.startup``; the API
    prints it during its call (progress on), not when progress is off or when the caller's
    own logging takes the record."""
    from orchestrator.run.progress import startup_log

    log = logging.getLogger("gsb.startup")
    root = logging.getLogger()
    monkeypatch.setattr(log, "handlers", [])  # nothing of the command line's left
    monkeypatch.setattr(log, "propagate", True)
    # the caller's logging configured (whatever other tests left on the root logger)
    monkeypatch.setattr(root, "handlers", [logging.NullHandler()])
    with startup_log(True):
        log.info("compiling the numba kernels")
    assert capsys.readouterr().err == ""
    monkeypatch.setattr(root, "handlers", [])
    with startup_log(True):
        log.info("compiling the numba kernels")
    assert capsys.readouterr().err == "gsb: compiling the numba kernels\n"
    with startup_log(False):
        log.info("compiling the numba kernels")
    assert capsys.readouterr().err == ""
    assert log.handlers == []


def test_the_command_line_leaves_no_log_handler_behind(capsys):
    """``main`` called in a process that goes on (a test, a script) removes the handler that
    printed its start-up log: a later library call would write to a closed stream."""
    import orchestrator.cli

    assert orchestrator.cli.main(["cases"]) == 0
    log = logging.getLogger("gsb.startup")
    assert log.handlers == [] and log.propagate and log.level == logging.NOTSET


def test_the_campbell_diagram_as_a_dataset():
    """Isotropic bearings: the modes at two speeds, 1-based, ascending; the paper's case has
    no gyroscopic terms, so the two speeds give the same frequencies; whirl labels are the
    four known words; bad speeds are one CaseError."""
    ds = gsb.campbell(SPUR, [200.0, 400.0], bearing_stiffness=1e8, progress=False)
    assert ds.frequency.dims == ("speed", "mode") and ds.mode.values[0] == 1
    f = ds.frequency.values
    assert np.all(np.diff(f[0][np.isfinite(f[0])]) >= 0.0)
    np.testing.assert_array_equal(f[0], f[1])
    assert set(ds.whirl_direction.values.ravel()) <= {"forward", "backward", "mixed", "none"}
    assert ds.speed.attrs["units"] == "rad/s" and ds.frequency.attrs["units"] == "Hz"
    assert math.isnan(ds.attrs["stability_threshold_rad_s"])
    with pytest.raises(CaseError, match="increasing"):
        gsb.campbell(SPUR, [400.0, 200.0], bearing_stiffness=1e8, progress=False)
