"""The gsb command line: bearing calculator forms, JSON keys, errors."""

import json
import math

import pytest

from orchestrator.cli import main


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
