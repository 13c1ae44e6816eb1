"""Results files keep what was computed when a run stops early."""

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from orchestrator.results import ResultsWriter, export_csv, read_results


def test_units_and_attributes_are_stored(tmp_path):
    path = tmp_path / "r.h5"
    with ResultsWriter(path, {"F": ((4, 2), "N", "bearing forces")},
                       attrs={"case": "demo", "settings": {"dt": 1e-4}}, block=3) as w:
        for k in range(7):
            w.append(time=k * 1e-4, F=np.full((4, 2), k))
    r = read_results(path)
    assert r["units"]["F"] == "N" and r["units"]["time"] == "s"
    assert r["F"].shape == (7, 4, 2) and r["F"][6, 3, 1] == 6
    assert r["attrs"]["complete"] and r["attrs"]["case"] == "demo"
    csv = export_csv(path, tmp_path / "r.csv")
    assert csv.read_text().splitlines()[0].startswith("time [s],F[0] [N]")


def test_exception_keeps_flushed_rows_and_marks_incomplete(tmp_path):
    path = tmp_path / "r.h5"
    with pytest.raises(KeyboardInterrupt):
        with ResultsWriter(path, {"x": ((), "m", "x")}, block=4) as w:
            for k in range(10):
                w.append(time=float(k), x=float(k))
                if k == 8:
                    raise KeyboardInterrupt
    r = read_results(path)
    assert not r["attrs"]["complete"] and "KeyboardInterrupt" in r["attrs"]["stopped_by"]
    np.testing.assert_array_equal(r["x"], np.arange(9.0))


def test_killed_process_keeps_flushed_blocks(tmp_path):
    """A hard kill (no clean-up at all) still leaves every flushed block readable."""
    path = tmp_path / "r.h5"
    code = textwrap.dedent(f"""
        import os
        from orchestrator.results import ResultsWriter
        w = ResultsWriter(r"{path}", {{"x": ((), "m", "x")}}, block=5)
        for k in range(12):
            w.append(time=float(k), x=float(k))
        os._exit(9)
    """)
    proc = subprocess.run([sys.executable, "-c", code], timeout=120)
    assert proc.returncode == 9
    r = read_results(path)
    np.testing.assert_array_equal(r["x"], np.arange(10.0))
