"""The gsb command line: bearing calculator forms, JSON keys, errors."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from orchestrator.cli import main
from tests.helpers import probe_env


def test_bearing_dimensionless_json(capsys):
    assert main(["bearing", "--model", "hybrid", "--l-over-d", "1", "--eccentricity", "0.6",
                 "--pinned-start", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    for key in ("force", "sommerfeld", "attitude_deg", "stiffness", "damping"):
        assert key in rep
    assert rep["sommerfeld"] == pytest.approx(0.121, rel=0.01)  # Raimondi & Boyd
    assert rep["attitude_deg"] == pytest.approx(50.58, abs=0.5)
    assert len(rep["stiffness"]) == 2 and len(rep["damping"][1]) == 2


def test_bearing_dimensional_static_and_png(capsys, tmp_path):
    png = tmp_path / "p.png"
    assert main(["bearing", "--model", "short", "--diameter", "0.07", "--length", "0.05",
                 "--clearance", "150e-6", "--viscosity", "0.0288", "--speed", "325",
                 "--load", "2251", "--json", "--pressure-png", str(png)]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["force_N"][1] == pytest.approx(2251.0, rel=1e-9)  # balances the load along -y
    assert 0.5 < rep["eccentricity"] < 0.7
    assert math.isfinite(rep["stiffness_N_per_m"][0][0])
    assert png.stat().st_size > 5000


def test_bearing_errors_are_clear(capsys):
    assert main(["bearing", "--l-over-d", "0.5", "--eccentricity", "1.2"]) == 2
    assert "--eccentricity 1.2: must be in [0, 1)" in capsys.readouterr().err
    assert main(["bearing", "--model", "short", "--diameter", "0.07", "--length", "0.05",
                 "--clearance", "-1", "--viscosity", "0.0288", "--speed", "325",
                 "--load", "10"]) == 2
    assert "--clearance -1: must be finite and > 0" in capsys.readouterr().err
    assert main(["bearing", "--model", "short", "--diameter", "0.07", "--length", "0.05",
                 "--clearance", "150e-6", "--viscosity", "0.0288", "--speed", "325",
                 "--load", "1e9"]) == 2
    assert "cannot carry" in capsys.readouterr().err


def _gsb(*args, cwd):
    return subprocess.run([sys.executable, "-m", "orchestrator.cli", *map(str, args)],
                          capture_output=True, text=True, timeout=300, cwd=cwd,
                          env=probe_env())


def test_gsb_export_names_columns_as_printed_and_keeps_an_existing_csv(tmp_path):
    """``gsb export --csv``: columns named by the file's labels of its bearings, gears and
    meshes and by axis s / t (as the prints and figures), each holding that component; a
    second export refuses to replace the CSV (exit 2, one line naming it and --overwrite)
    and leaves it as it was; --overwrite replaces it."""
    from orchestrator.run.channels import channels, dims
    from orchestrator.run.results import ResultsWriter

    path = tmp_path / "run.h5"
    coords = {"bearing": ("in_a", "in_b", "out_a"), "gear": ("pinion", "wheel"),
              "mesh": ("stage1",), "shaft": ("input", "output"), "axis": ("s", "t")}
    table = channels(coords)
    names = ("journal_position", "bearing_force", "gear_node", "mesh_force")
    rng = np.random.default_rng(3)
    rows = {n: rng.normal(size=(5, *table[n][0])) for n in names}
    with ResultsWriter(path, {n: table[n] for n in names}, attrs={"kind": "run"}, dims=dims,
                       coords=coords) as w:
        for k in range(5):
            w.append(time=1e-4 * (k + 1), **{n: rows[n][k] for n in names})
    csv = tmp_path / "run.csv"
    done = _gsb("export", path, "--csv", csv, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    lines = csv.read_text().splitlines()
    head = lines[0].split(",")
    first = head.index("journal_position[bearing=in_a][axis=s] [m]")
    assert head[0] == "time [s]"
    assert head[first + 1] == "journal_position[bearing=in_a][axis=t] [m]"
    values = np.array([[float(x) for x in line.split(",")] for line in lines[1:]])
    column = head.index("bearing_force[bearing=out_a][axis=t] [N]")
    assert values[:, column].tolist() == rows["bearing_force"][:, 2, 1].tolist()
    column = head.index("gear_node[gear=wheel][axis=s] [m]")
    assert values[:, column].tolist() == rows["gear_node"][:, 1, 0].tolist()
    assert "mesh_force[mesh=stage1] [N]" in head
    assert not any("[0]" in h or "=0]" in h or "[1]" in h for h in head)
    csv.write_text("kept\n")
    again = _gsb("export", path, "--csv", csv, cwd=tmp_path)
    assert again.returncode == 2 and csv.read_text() == "kept\n"
    assert again.stderr.startswith(f"gsb export: error: --csv {csv}: exists")
    assert "--overwrite" in again.stderr and again.stderr.count("\n") == 1
    forced = _gsb("export", path, "--csv", csv, "--overwrite", cwd=tmp_path)
    assert forced.returncode == 0 and csv.read_text().splitlines()[0] == lines[0]
