"""The paper's section 4 on short runs (default suite) and the whole reproduction (slow).

Short runs are not steady state (the paper runs 2048 mesh periods); each check is one that
holds from the first gear revolutions on. ``gsb reproduce`` runs the full-length version.
"""

import itertools
import math

import numpy as np
import pytest

from fmu_src.case import load_case
from fmu_src.examples import HELICAL, SPUR
from orchestrator.analysis.metrics import fit_ellipse, run_metrics, steady_window
from orchestrator.coupling.system import build_master
from orchestrator.run.results import read_results
from orchestrator.run.runner import run_case
from orchestrator.studies.reproduce.figures import force_spectrum, has_line


def short_run(tmp_path, path=SPUR, model="hybrid", periods=192, **overrides):
    case = load_case(path, overrides)
    run = {"bearings.*.model": model, "simulation.mesh_periods": periods}
    s = run_case(case.with_overrides(run), in_process=True, out_dir=tmp_path, progress=False)
    return read_results(s.results), s


@pytest.fixture(scope="module")
def spur(tmp_path_factory):
    """Spur case, hybrid bearings, 192 mesh periods (> one gear revolution of 157)."""
    return short_run(tmp_path_factory.mktemp("spur"))


def test_bearing_force_spectra_have_the_papers_lines(spur):
    """Fig. 7: bearing 1 at 1 and 26 (and harmonics of 26) in pinion rotation units; bearing 3
    at 1, 157/26 and 157 in gear rotation units; nothing at frequencies no source has."""
    r, _ = spur
    f, a, res = force_spectrum(r, 0, revolutions=4.0)
    for line in (1.0, 26.0, 52.0, 78.0):
        assert has_line(f, a, line, res), line
    for none in (13.0, 30.5, 40.0):
        assert not has_line(f, a, none, res), none
    f, a, res = force_spectrum(r, 2)
    for line in (1.0, 157 / 26, 157.0, 314.0):
        assert has_line(f, a, line, res), line
    for none in (3.3, 100.0):
        assert not has_line(f, a, none, res), none


def test_spur_orbits_are_centred_on_the_static_position(spur):
    """Figs. 5, 12a: orbits of the spur case around X0 (ellipse centre within 5 % of C)."""
    r, s = spur
    win = steady_window(r["time"], 2 * math.pi / 325.0 * 4)
    for b, c in enumerate((150e-6, 150e-6, 110e-6, 110e-6)):
        o = r["journal_position"][win, b]
        centre = fit_ellipse(o[:, 0], o[:, 1])["centre"]
        assert np.hypot(*(centre - s.static_positions[b])) < 0.05 * c


def test_helical_orbits_shift_to_either_side(tmp_path):
    """Fig. 12: with the helical pair the mesh moment tilts the shafts: the static positions of
    bearings 1 and 2 (and 3 and 4) part, on opposite sides of their mean."""
    master = build_master(load_case(HELICAL), in_process=True)
    master.solve_static()
    x0 = master.structure.journal_states()[:, :2]
    for b1, b2, c in ((0, 1, 150e-6), (2, 3, 110e-6)):
        mid = 0.5 * (x0[b1] + x0[b2])
        d1, d2 = x0[b1] - mid, x0[b2] - mid
        assert np.hypot(*d1) > 0.02 * c
        assert np.dot(d1, d2) < 0


def test_mean_eccentricity_grows_with_torque():
    """Fig. 9: the static position (the centre of the orbits) moves out with the torque."""
    ecc = []
    for torque in (50.0, 100.0, 220.0, 400.0, 600.0):
        master = build_master(load_case(SPUR, {"drive.torque": torque}), in_process=True)
        master.solve_static()
        ecc.append(np.hypot(*master.structure.journal_states()[0, :2]) / 150e-6)
    assert all(a < b for a, b in itertools.pairwise(ecc))
    print("\nbearing 1 eccentricity at T = 50 ... 600 N m: " + ", ".join(f"{e:.3f}" for e in ecc))


def test_linear_and_nonlinear_bearings_agree_at_small_unbalance(tmp_path):
    """Sec. 4.2.2 / Fig. 7: with e_mu = 0.6 mm the journals stay near X0 and the 8-coefficient
    model gives the same bearing forces as the hybrid model; with 4 times the unbalance at
    high speed the two part further (Fig. 10a)."""
    diffs = {}
    for e, speed in (("0.6 mm", 325.0), ("2.4 mm", 900.0)):
        m = {}
        for model in ("hybrid", "linear"):
            r, _ = short_run(tmp_path, model=model, periods=96,
                             **{"gears.*.unbalance": e, "drive.speed": speed})
            m[model] = run_metrics(r, 26 * 2 * math.pi / (speed * 26))
        diffs[e] = abs(m["linear"]["force_ptp"][0] / m["hybrid"]["force_ptp"][0] - 1)
    print(f"\nbearing-1 peak-to-peak, linear vs nonlinear: {100 * diffs['0.6 mm']:.1f} % at "
          f"e_mu 0.6 mm, 325 rad/s; {100 * diffs['2.4 mm']:.1f} % at 2.4 mm, 900 rad/s")
    assert diffs["0.6 mm"] < 0.05
    assert diffs["2.4 mm"] > diffs["0.6 mm"]


def test_helical_pair_lowers_the_dynamic_tooth_load(tmp_path, spur):
    """Fig. 11a: R falls as the helix angle grows (at the paper's operating point)."""
    r, _ = spur
    window = 26 * 2 * math.pi / (325.0 * 26)
    r_spur = run_metrics(r, window)["R"][0]  # the pair's one mesh
    rh, _ = short_run(tmp_path, HELICAL, periods=96)
    r_helical = run_metrics(rh, window)["R"][0]
    print(f"\nR at 325 rad/s: spur {r_spur:.3f}, helical 12.5 deg {r_helical:.3f}")
    assert 1.0 < r_helical < r_spur


@pytest.mark.slow
def test_quick_reproduction_end_to_end(tmp_path):
    """``gsb reproduce --quick``: every figure and the report, the checks that hold on short
    runs pass (the full-length checks are quoted from ``gsb reproduce``)."""
    from orchestrator.studies.reproduce import reproduce

    report = reproduce(tmp_path, quick=True, progress=False)
    text = report.read_text()
    for fig in ("fig05_06_orbits", "fig07_forces", "fig08_speed", "fig09_torque",
                "fig10_unbalance", "fig11_14_helix", "fig12_17_transients", "fig13_face_load",
                "fig15_forces", "fig16_models"):
        assert (tmp_path / "figures" / f"{fig}.png").is_file(), fig
    for check in ("bearing 1 spectrum", "spur: orbits 1 = 2", "helical: orbits 1 and 2",
                  "mean shaft eccentricity grows", "Table 4: time linear < hybrid",
                  "short-bearing theory far off"):
        line = next(ln for ln in text.splitlines() if check in ln)
        assert line.endswith("PASS |"), line
