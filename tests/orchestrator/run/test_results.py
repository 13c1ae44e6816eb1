"""Results files keep what was computed when a run stops early."""

import subprocess

import numpy as np
import pytest

from orchestrator.run.results import ResultsWriter, export_csv, read_results
from tests.helpers import probe_command, probe_env


def test_units_and_attributes_are_stored(tmp_path):
    path = tmp_path / "r.h5"
    with ResultsWriter(path, {"F": ((4, 2), "N", "bearing forces")},
                       attrs={"case": "demo", "clearance": [1e-4, 2e-4]}, capacity=3) as w:
        for k in range(7):
            w.append(time=k * 1e-4, F=np.full((4, 2), k))
    r = read_results(path)
    assert r["units"]["F"] == "N" and r["units"]["time"] == "s"
    assert r["F"].shape == (7, 4, 2) and r["F"][6, 3, 1] == 6
    assert r["attrs"]["complete"] and r["attrs"]["case"] == "demo"
    assert r["attrs"]["clearance"].dtype == np.float64  # numeric, not JSON text
    csv = export_csv(path, tmp_path / "r.csv")
    head, first = csv.read_text().splitlines()[:2]
    # a channel the results channels do not describe: components numbered from 1
    assert head.startswith("time [s],F[1][1] [N],F[1][2] [N],F[2][1] [N]")
    assert [float(x) for x in first.split(",")] == [0.0] * 9


def test_exception_keeps_flushed_rows_and_marks_incomplete(tmp_path):
    path = tmp_path / "r.h5"
    with pytest.raises(KeyboardInterrupt):
        with ResultsWriter(path, {"x": ((), "m", "x")}, capacity=4) as w:
            for k in range(10):
                w.append(time=float(k), x=float(k))
                if k == 8:
                    raise KeyboardInterrupt
    r = read_results(path)
    assert not r["attrs"]["complete"] and "KeyboardInterrupt" in r["attrs"]["stopped_by"]
    np.testing.assert_array_equal(r["x"], np.arange(9.0))


def test_rows_appended_in_blocks_are_the_rows_appended_one_by_one(tmp_path):
    """Blocks of 5 rows through a buffer of 3 (``append_rows``, the runner's blocks of
    steps): the same file as row by row. A checkpoint is the state after the last row of the
    block it follows: taken only once the whole block is in (its row count), never in the
    middle of one, and not after a block appended without a flush (a block ended by a failed
    step)."""
    from orchestrator.run.results import read_checkpoint

    def channels():
        return {"F": ((4, 2), "N", "bearing forces")}

    rows = np.arange(20 * 8, dtype=float).reshape(20, 4, 2)
    with ResultsWriter(tmp_path / "one.h5", channels(), capacity=3) as w:
        for k in range(20):
            w.append(time=k * 1e-4, F=rows[k])
    calls = []  # the rows stored when each checkpoint was taken

    def checkpoint():
        calls.append(w.rows)
        return str(w.rows).encode()

    with ResultsWriter(tmp_path / "blocks.h5", channels(), capacity=3, flush_seconds=0.0,
                       checkpoint=checkpoint) as w:
        for first in range(0, 15, 5):
            w.append_rows(5, time=np.arange(first, first + 5) * 1e-4, F=rows[first:first + 5])
            assert read_checkpoint_now(w) == (first + 5, str(first + 5).encode())
        w.append_rows(5, flush=False, time=np.arange(15, 20) * 1e-4, F=rows[15:])
        w.close(complete=False, checkpoint=False)
    one, blocks = read_results(tmp_path / "one.h5"), read_results(tmp_path / "blocks.h5")
    for name in ("time", "F"):
        np.testing.assert_array_equal(blocks[name], one[name])
    assert calls == [5, 10, 15]
    assert read_checkpoint(tmp_path / "blocks.h5") == (15, b"15")


def read_checkpoint_now(w):
    """The writer's last checkpoint, read from its open file: (rows, state bytes)."""
    slot, size, rows = (int(v) for v in w.file["resume/index"][:])
    return rows, bytes(w.file[f"resume/slot{slot}"][:size])


def test_killed_process_keeps_flushed_blocks(tmp_path):
    """A hard kill (no clean-up at all) still leaves every flushed block readable."""
    path = tmp_path / "r.h5"
    proc = subprocess.run(probe_command("tests.probes.results", "killed_writer", {"path": path}),
                          timeout=120, env=probe_env())
    assert proc.returncode == 9
    r = read_results(path)
    np.testing.assert_array_equal(r["x"], np.arange(10.0))


def test_xarray_opens_a_run_file_with_the_names_and_dimensions_of_the_api(tmp_path):
    """A results file of a run (4 mesh periods in-process) opened by xarray through h5netcdf:
    every channel on its named dimensions (time, bearing, mesh, gear labelled by the case's
    names, axis s/t), the labels as coordinates, the units in ``units``, the values those h5py
    reads, and the same Dataset (variables, dimensions, coordinates) as the in-memory
    result's ``to_xarray()`` of the same run; the CSV export's columns carry the same labels."""
    import xarray as xr

    import orchestrator as gsb

    written = gsb.simulate("baguet2010_spur", periods=4, in_process=True, progress=False,
                           results_dir=tmp_path)
    path = written.summary.results
    raw = read_results(path)
    assert raw["coords"] == {"bearing": ("1", "2", "3", "4"), "axis": ("s", "t"),
                             "mesh": ("mesh",), "gear": ("pinion", "gear"),
                             "shaft": ("pinion_shaft", "gear_shaft")}
    with xr.open_dataset(path, engine="h5netcdf") as ds:
        assert dict(ds.sizes) == {"time": 128, "bearing": 4, "axis": 2, "mesh": 1, "gear": 2,
                                  "shaft": 2}
        assert ds.shaft_speed.dims == ("time", "shaft")
        assert ds.shaft_speed.attrs["units"] == "rad/s"
        assert ds.journal_position.dims == ("time", "bearing", "axis")
        assert ds.gear_node.dims == ("time", "gear", "axis")
        assert ds.mesh_force.dims == ("time", "mesh")
        assert ds.transmission_error.dims == ("time", "mesh")
        assert list(ds.bearing.values) == ["1", "2", "3", "4"]
        assert list(ds.axis.values) == ["s", "t"]
        assert list(ds.gear.values) == ["pinion", "gear"]
        assert ds.bearing_force.attrs["units"] == "N"
        assert ds.journal_position.attrs["units"] == "m"
        for name in ("journal_position", "bearing_force", "mesh_force", "gear_node"):
            assert np.array_equal(ds[name].values, raw[name]), name
        assert np.array_equal(ds.time.values, raw["time"])
        # bearing 3, t: the labelled selection is the raw array's [:, 2, 1]
        assert np.array_equal(ds.journal_position.sel(bearing="3", axis="t").values,
                              raw["journal_position"][:, 2, 1])
        memory = gsb.simulate("baguet2010_spur", periods=4, in_process=True,
                              progress=False).to_xarray()
        assert set(memory.data_vars) == set(ds.data_vars)
        for name in memory.data_vars:
            assert memory[name].dims == ds[name].dims, name
            assert np.array_equal(memory[name].values, ds[name].values), name
        for dim in ("bearing", "mesh", "gear", "axis"):
            assert list(memory[dim].values) == list(ds[dim].values), dim
    head = export_csv(path, tmp_path / "r.csv").read_text().splitlines()[0].split(",")
    assert "journal_position[bearing=3][axis=t] [m]" in head
    assert "gear_node[gear=pinion][axis=s] [m]" in head
    assert "mesh_force[mesh=mesh] [N]" in head


def test_read_result_names_a_missing_or_foreign_file(tmp_path):
    """``read_result`` of no file, of a file that is not HDF5, and of an HDF5 file that is no
    run's: FileNotFoundError or ValueError naming the file and why, never h5py's own error."""
    import orchestrator as gsb

    with pytest.raises(FileNotFoundError, match="no such results file"):
        gsb.read_result(tmp_path / "missing.h5")
    text = tmp_path / "notes.h5"
    text.write_text("not HDF5")
    with pytest.raises(ValueError, match=r"notes\.h5: not a readable results file"):
        gsb.read_result(text)
    other = tmp_path / "other.h5"
    with ResultsWriter(other, {"x": ((), "m", "a length")}, {"kind": "sweep"}) as w:
        w.append(time=0.0, x=1.0)
    with pytest.raises(ValueError, match=r"other\.h5: not a results file of a run"):
        gsb.read_result(other)


def test_a_runs_csv_starts_at_rest_at_x0(tmp_path):
    """The CSV of a run starts at t = 0 with the static solution X0 the file stores (the
    journals at their static positions at rest, the static bearing and mesh forces, the
    gear nodes at X0), then one row per step; a file without the gear nodes' static
    positions (an older version's) starts at the first step and says so once."""
    import h5py

    from orchestrator.run.results import OlderFileWarning
    from tests.helpers import run_paper_case

    results, summary = run_paper_case(tmp_path, periods=1)
    attrs = results["attrs"]
    lines = export_csv(summary.results, tmp_path / "r.csv").read_text().splitlines()
    head = lines[0].split(",")
    rows = np.array([[float(x) for x in line.split(",")] for line in lines[1:]])
    assert len(rows) == 32 + 1 and rows[0, 0] == 0.0 and rows[1, 0] == results["time"][0]

    def at_rest(label):
        return rows[0, head.index(label)]

    assert at_rest("journal_position[bearing=3][axis=t] [m]") == attrs["static_journal"][2, 1]
    assert at_rest("journal_velocity[bearing=3][axis=t] [m/s]") == 0.0
    assert at_rest("bearing_force[bearing=1][axis=s] [N]") == \
        attrs["static_bearing_force"][0, 0]
    assert at_rest("mesh_force[mesh=mesh] [N]") == attrs["static_mesh_force"][0]
    assert at_rest("gear_node[gear=pinion][axis=t] [m]") == attrs["static_gear_node"][0, 1]
    assert rows[1, head.index("journal_position[bearing=3][axis=t] [m]")] == \
        results["journal_position"][0, 2, 1]
    with h5py.File(summary.results, "a") as f:
        del f.attrs["static_gear_node"]
    with pytest.warns(OlderFileWarning, match="no row at t = 0 .*static_gear_node"):
        older = export_csv(summary.results, tmp_path / "old.csv").read_text().splitlines()
    assert len(older) == 32 + 1  # the header and the steps
