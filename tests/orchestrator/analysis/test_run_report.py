"""The report of ``gsb run``: order lines by least squares, R and the bearing-force
peak-to-peak over the last revolution of the slowest shaft (the paper's gear; or the last half
of a shorter run), stored as numeric root attributes of the results file; the same for a
two-stage train, per mesh and per bearing by name."""

import math

import h5py
import numpy as np
import pytest

from fmu_src.case import load_case
from orchestrator.analysis.metrics import run_report
from orchestrator.analysis.spectrum import order_lines, resolved_lines
from orchestrator.run.results import read_results
from orchestrator.run.runner import run_case
from orchestrator.run.spec import RunError
from tests.helpers import fail_master_step, run_here

SPUR = "baguet2010_spur"
Z1, Z2 = 26, 157
OMEGA = 325.0  # rad/s, pinion
F1 = OMEGA / (2 * math.pi)  # Hz, pinion 1x
DT = 1.0 / (Z1 * F1 * 32)  # s, 32 steps per mesh period
# order_lines is exact for a noiseless sum of the fitted lines: the error is round-off of the
# least-squares solve, measured 1.6e-14 (relative, over one gear revolution; printed by the
# first test): asserted at 1e-10, a margin of ~6000. A plain rFFT misses the 1x line by 5.4e-3.
TOL = 1e-10


def paper_lines():
    """(frequencies [Hz], amplitudes [N], phases [rad]) of 1x, gear 1x, 26x, 52x, 78x."""
    freqs = F1 * np.array([1.0, Z1 / Z2, Z1, 2 * Z1, 3 * Z1])
    return freqs, np.array([184.0, 70.4, 239.3, 1077.4, 1099.6]), \
        np.array([0.3, 1.0, -2.0, 0.5, 2.0])


def lines_signal(t, mean, freqs, amps, phases):
    return mean + sum(a * np.cos(2 * np.pi * f * t + p)
                      for f, a, p in zip(freqs, amps, phases, strict=True))


def static_load():
    """T / r_b1 [N] of the spur case, r_b1 = m z1 cos(alpha) / 2 (spur: beta_b = 0)."""
    return 220.0 / (0.004 * Z1 * math.cos(math.radians(20.0)) / 2)


def test_order_lines_over_one_gear_revolution_where_an_fft_leaks():
    """One gear revolution (157 mesh periods, 32 samples each) holds 157/26 = 6.04 pinion
    revolutions: the 1x line is not periodic in the window, the gear 1x and mesh lines are."""
    t = 0.2639 + DT * np.arange(1, Z2 * 32 + 1)  # a window late in a run
    freqs, amps, phases = paper_lines()
    periods_1x = freqs[0] * t.size * DT  # 157/26 = 6.04
    assert abs(periods_1x - 157 / 26) < 1e-12 and abs(periods_1x - 6) > 0.03
    y = lines_signal(t, 3000.0, freqs, amps, phases)
    got = order_lines(t, y, freqs)
    error = np.abs(got / amps - 1).max()
    # a plain rFFT of the window: bin spacing 1/T = the gear frequency, the 1x line falls at
    # bin 6.04 and leaks (scalloping); the gear and mesh lines sit on bins 1, 157, 314, 471
    spectrum = 2 * np.abs(np.fft.rfft(y)) / t.size
    fft_error = abs(spectrum[6] / amps[0] - 1)
    print(f"\norder_lines over 6.04 pinion periods: max relative error {error:.1e} "
          f"(tolerance {TOL:.0e}); rFFT peak of the 1x line: {fft_error:.1e}")
    assert error < TOL
    assert fft_error > 1e3 * TOL  # the test discriminates: an FFT fails it by orders
    # trailing axes are independent signals (the four bearings at once)
    both = order_lines(t, np.column_stack([y, 2 * y - 5.0]), freqs)
    assert both.shape == (5, 2)
    np.testing.assert_allclose(both[:, 1], 2 * amps, rtol=TOL)


def test_order_lines_rejects_too_few_samples_and_inseparable_lines():
    t = DT * np.arange(10)
    with pytest.raises(ValueError, match="10 samples cannot fit a mean and 5 lines: need at "
                                         "least 11"):
        order_lines(t, np.ones(10), paper_lines()[0])
    with pytest.raises(ValueError, match=r"not separable over .* rank 3 of 5"):
        order_lines(t, np.ones(10), [1000.0, 1000.0])
    with pytest.raises(ValueError, match=r"time_s has shape \(10,\), signal \(9,\)"):
        order_lines(t, np.ones(9), [1000.0])


def test_resolved_lines_of_the_report():
    freqs = paper_lines()[0]
    gear_rev = Z2 * 32 * DT
    assert resolved_lines(freqs, gear_rev, DT).all()
    # four mesh periods: a fraction of a pinion revolution, the mesh lines only
    assert resolved_lines(freqs, 4 * 32 * DT, DT).tolist() == [False, False, True, True, True]
    # half a mesh period short of a gear revolution: the gear line is not resolved
    assert resolved_lines(freqs, gear_rev - 16 * DT, DT).tolist() == [True, False, True,
                                                                        True, True]


def hand_built_results(n_steps):
    """A results dict of the spur case with known R, ptp and lines over its window.

    Bearing 1: ||F|| in [2800, 3200] with 3900 and 2100 planted in the window (9999 before
    it): ptp 1800 N. Bearing 2: the five lines of :func:`paper_lines` on a mean of 4000 N.
    Bearing 3: 2000 + 300 cos(2 pi f_mesh t), sampled on its extremes: ptp 600, 26x 300 N.
    Bearing 4: a constant 1500 N. The force direction turns with the pinion. The mesh force
    has 1.75 W0 planted in the window and 2.5 W0 before it: R = 1.75.
    """
    t = DT * np.arange(1, n_steps + 1)
    # first index in the window: the last gear revolution, or the last half
    window_start = n_steps - Z2 * 32 if n_steps >= Z2 * 32 else n_steps // 2
    w0 = static_load()
    mesh = w0 * (1 + 0.2 * np.sin(2 * np.pi * Z1 * F1 * t + 0.1))
    mesh[window_start // 2] = 2.5 * w0
    mesh[window_start + 37] = 1.75 * w0
    freqs, amps, phases = paper_lines()
    norm = np.empty((n_steps, 4))
    norm[:, 0] = 3000 + 200 * np.sin(2 * np.pi * 3.7 * F1 * t)
    norm[window_start // 3, 0] = 9999.0
    norm[window_start + 11, 0] = 3900.0
    norm[n_steps - 5, 0] = 2100.0
    norm[:, 1] = lines_signal(t, 4000.0, freqs, amps, phases)
    norm[:, 2] = 2000 + 300 * np.cos(2 * np.pi * Z1 * F1 * t)
    norm[:, 3] = 1500.0
    angle = 2 * np.pi * F1 * t
    force = norm[:, :, None] * np.stack([np.cos(angle), np.sin(angle)], axis=-1)[:, None, :]
    attrs = {"case_toml": load_case(SPUR).to_toml(), "case_file": SPUR}
    return {"time": t, "mesh_force": mesh, "bearing_force": force, "attrs": attrs}, amps


def test_run_report_over_the_last_gear_revolution():
    n = Z2 * 32 + 800
    results, amps = hand_built_results(n)
    r = run_report(results)
    t_end = n * DT
    assert r["window_kind"] == "last revolution of the slowest shaft gear_shaft"
    np.testing.assert_allclose(r["window_s"], [t_end - 2 * math.pi * Z2 / (Z1 * OMEGA), t_end],
                               rtol=1e-14)
    print(f"\nR = {r['dynamic_factor']!r}, ptp = {r['bearing_force_ptp']}")
    # 1.75 W0 / W0 and hypot(n cos, n sin) of planted values: round-off only
    assert r["dynamic_factor"].shape == (1,) and r["mesh_names"] == ["mesh"]
    assert r["dynamic_factor"][0] == pytest.approx(1.75, rel=1e-15)
    assert r["bearing_names"] == ["1", "2", "3", "4"]
    assert r["bearing_force_ptp"][0] == pytest.approx(1800.0, rel=1e-13)
    assert r["bearing_force_ptp"][2] == pytest.approx(600.0, rel=1e-12)
    assert r["bearing_force_ptp"][3] < 1e-9 * 1500
    assert r["line_labels"] == ["pinion_shaft_1x", "gear_shaft_1x", "mesh_GMF", "mesh_2GMF",
                                "mesh_3GMF"]
    np.testing.assert_allclose(r["line_frequencies"], paper_lines()[0], rtol=1e-15)
    # in orders of each bearing's shaft: the pinion's for bearings 1, 2, the gear's for 3, 4
    pinion = [1, Z1 / Z2, 26, 52, 78]
    np.testing.assert_allclose(r["line_orders"], [pinion, pinion] + [
        [q * Z2 / Z1 for q in pinion]] * 2, rtol=1e-14)
    assert r["line_orders"][2].tolist()[1:] == pytest.approx([1, 157, 314, 471], rel=1e-14)
    assert r["line_amplitudes"].shape == (4, 5)
    np.testing.assert_allclose(r["line_amplitudes"][1], amps, rtol=TOL)
    np.testing.assert_allclose(r["line_amplitudes"][2], [0, 0, 300.0, 0, 0], rtol=TOL,
                               atol=TOL * 300)
    np.testing.assert_allclose(r["line_amplitudes"][3], 0.0, atol=TOL * 1500)


def test_run_report_over_the_last_half_of_a_short_run():
    """8 mesh periods: the window is the last 4 (128 samples); the 1x and gear lines are not
    resolved there (NaN), the mesh lines are, R and the ptp ignore the first half."""
    n = 8 * 32
    results = hand_built_results(n)[0]
    r = run_report(results)
    assert r["window_kind"] == "last half of the run"
    np.testing.assert_allclose(r["window_s"], [n * DT / 2, n * DT], rtol=1e-15)
    assert r["dynamic_factor"] == pytest.approx([1.75], rel=1e-15)
    assert r["bearing_force_ptp"][0] == pytest.approx(1800.0, rel=1e-13)
    assert np.isnan(r["line_amplitudes"][:, :2]).all()
    # bearing 3 holds only the 26x line and its mean: exact over the 4 periods
    np.testing.assert_allclose(r["line_amplitudes"][2, 2:], [300.0, 0, 0], atol=TOL * 300)
    # 2 steps: the last one alone, no line resolved
    two = {k: v if k == "attrs" else v[:2] for k, v in results.items()}
    r2 = run_report(two)
    assert r2["dynamic_factor"] == [results["mesh_force"][1] / static_load()]
    assert (r2["bearing_force_ptp"] == 0).all() and np.isnan(r2["line_amplitudes"]).all()
    with pytest.raises(ValueError, match="at least 2 time steps, got 1"):
        run_report({k: v if k == "attrs" else v[:1] for k, v in results.items()})


@pytest.mark.parametrize("window, duration, name", [
    ("26 periods", 26 * 2 * math.pi / (Z1 * OMEGA), "last 26 mesh periods"),
    ("2 revolutions of pinion_shaft", 2 * 2 * math.pi / OMEGA,
     "last 2 revolutions of pinion_shaft"),
    ("1 rev of gear_shaft", 2 * math.pi * Z2 / (Z1 * OMEGA), "last 1 revolution of gear_shaft"),
    ("10 ms", 0.01, "last 0.01 s")])
def test_run_report_over_a_stated_window(window, duration, name):
    """``simulation.window`` in periods, revolutions of a named shaft or seconds: the report's
    window is the last ``duration`` (from the teeth and the speed by hand), named so, and R
    and the peak-to-peak are the extremes of the channels over the steps ending in it."""
    n = Z2 * 32 + 800
    results = hand_built_results(n)[0]
    results["attrs"]["case_toml"] = load_case(SPUR, {"simulation.window": window}).to_toml()
    r = run_report(results)
    t = results["time"]
    np.testing.assert_allclose(r["window_s"], [t[-1] - duration, t[-1]], rtol=1e-14)
    assert r["window_kind"] == name
    inside = t > t[-1] - duration * (1 - 1e-9)
    assert inside.sum() == math.ceil(duration / DT - 1e-6)  # the steps ending in it
    norm = np.hypot(*np.moveaxis(results["bearing_force"][inside], -1, 0))
    assert r["dynamic_factor"][0] == pytest.approx(
        results["mesh_force"][inside].max() / static_load(), rel=1e-14)
    np.testing.assert_allclose(r["bearing_force_ptp"], np.ptp(norm, axis=0), rtol=1e-12,
                               atol=1e-9)


def test_a_stated_window_longer_than_the_run_or_unreadable_is_refused(tmp_path):
    """Before the run (its length in steps and seconds in the message), and when reporting a
    stored run; an unknown shaft gets the closest name, text that is no window the forms."""
    from fmu_src.case import CaseError

    case = load_case(SPUR, {"simulation.window": "2 revolutions of gear_shaft",
                            "simulation.mesh_periods": 64})
    with pytest.raises(RunError, match=r"simulation.window = '2 revolutions of gear_shaft' "
                                       r"\(0.2335 s\) is longer than the run \(2048 steps"):
        run_case(case, in_process=True, out_dir=tmp_path, progress=False)
    assert not list(tmp_path.iterdir())  # nothing run, nothing written
    results = hand_built_results(Z2 * 32 + 800)[0]
    results["attrs"]["case_toml"] = load_case(SPUR, {"simulation.window": "0.5 s"}).to_toml()
    with pytest.raises(ValueError, match=r"'0.5 s' \(0.5 s\) is longer than the run"):
        run_report(results)
    with pytest.raises(CaseError, match=r"no shaft 'gearshaft'.*did you mean gear_shaft"):
        load_case(SPUR, {"simulation.window": "1 revolution of gearshaft"})
    with pytest.raises(CaseError, match=r"cannot read '3 kg' as a window: write '26 periods'"):
        load_case(SPUR, {"simulation.window": "3 kg"})
    with pytest.raises(CaseError, match="the window must be longer than 0"):
        load_case(SPUR, {"simulation.window": "0 periods"})


def test_gsb_run_stores_the_report_as_numeric_attributes(tmp_path):
    """Through the pipeline: the spur case, linear bearings, 8 mesh periods in-process."""
    case = load_case(SPUR, {"bearings.*.model": "linear"})
    s = run_case(case.with_overrides({"simulation.mesh_periods": 8}), in_process=True,
                 out_dir=tmp_path, progress=False)
    keys = ("dynamic_factor", "transmission_error_ptp", "bearing_force_ptp", "line_amplitudes",
            "line_orders", "line_frequencies", "line_labels", "report_window",
            "report_window_kind")
    with h5py.File(s.results, "r") as f:
        a = {k: f.attrs[k] for k in keys}
        units = {k: f.attrs[f"{k}_unit"] for k in a if k not in ("line_labels",
                                                                  "report_window_kind")}
    shapes = {k: np.shape(v) for k, v in a.items()}
    assert shapes == {"dynamic_factor": (1,), "transmission_error_ptp": (1,),
                      "bearing_force_ptp": (4,), "line_amplitudes": (4, 5),
                      "line_orders": (4, 5), "line_frequencies": (5,), "line_labels": (5,),
                      "report_window": (2,), "report_window_kind": ()}
    for k in ("dynamic_factor", "transmission_error_ptp", "bearing_force_ptp",
              "line_amplitudes", "line_orders", "line_frequencies", "report_window"):
        assert a[k].dtype == np.float64, k
    assert [str(x) for x in a["line_labels"]] == ["pinion_shaft_1x", "gear_shaft_1x",
                                                  "mesh_GMF", "mesh_2GMF", "mesh_3GMF"]
    assert str(a["report_window_kind"]) == "last half of the run"
    assert units == {"dynamic_factor": "1", "transmission_error_ptp": "m",
                     "bearing_force_ptp": "N", "line_amplitudes": "N", "line_orders": "1",
                     "line_frequencies": "Hz", "report_window": "s"}
    # independent recomputation from the datasets
    r = read_results(s.results)
    assert r["time"].shape == (256,) and r["mesh_force"].shape == (256, 1)
    win = slice(128, None)  # the last half of the run
    assert a["dynamic_factor"][0] == r["mesh_force"][win].max() / static_load()
    assert a["transmission_error_ptp"][0] == np.ptp(r["transmission_error"][win])
    fb = np.hypot(r["bearing_force"][win, :, 0], r["bearing_force"][win, :, 1])
    np.testing.assert_array_equal(a["bearing_force_ptp"], np.ptp(fb, axis=0))
    np.testing.assert_array_equal(a["report_window"], [r["time"][-1] / 2, r["time"][-1]])
    assert np.isnan(a["line_amplitudes"][:, :2]).all()
    assert (np.isfinite(a["line_amplitudes"][:, 2:]) & (a["line_amplitudes"][:, 2:] > 0)).all()
    # the summary carries the same report, and prints it
    np.testing.assert_array_equal(s.report["line_amplitudes"], a["line_amplitudes"])
    assert s.report["dynamic_factor"] == a["dynamic_factor"]
    text = s.report_text()
    print("\n" + text)
    assert text.startswith("report over the last half of the run (t = ")
    assert f"dynamic factor R = {a['dynamic_factor'][0]:.3f}, transmission error " in text
    assert f"1: {a['bearing_force_ptp'][0]:.0f}, 2: " in text
    row = next(line for line in text.splitlines() if line.startswith("pinion_shaft_1x"))
    assert row.split()[2:] == ["-"] * 4  # not resolved by 4 mesh periods, at any bearing
    assert "bearings 3, 4: pinion_shaft_1x 6.038, gear_shaft_1x 1, mesh_GMF 157" in text
    assert s.describe().startswith("256 steps in ")


def test_a_failing_run_stores_the_report_of_what_it_kept(tmp_path, monkeypatch):
    fail_master_step(monkeypatch, at=201)
    case = load_case(SPUR, {"bearings.*.model": "linear"})
    with pytest.raises(RunError, match="step 201 of 256"):
        run_case(case.with_overrides({"simulation.mesh_periods": 8}), in_process=True,
                 out_dir=tmp_path, progress=False)
    r = read_results(next(tmp_path.glob("baguet2010_spur_linear_inprocess_*.h5")))
    assert r["time"].shape == (200,) and not r["attrs"]["complete"]
    win = slice(100, None)
    assert r["attrs"]["dynamic_factor"] == [r["mesh_force"][win].max() / static_load()]


def test_a_single_step_has_no_report(tmp_path):
    case = load_case(SPUR, {"bearings.*.model": "linear"})
    s = run_case(case, in_process=True, out_dir=tmp_path, progress=False,
                 steps=1)
    assert s.report is None
    assert s.report_text() == "no report: 1 step(s), at least 2 needed"
    assert "dynamic_factor" not in read_results(s.results)["attrs"]


def test_the_fmu_transport_stores_the_report(fmu_dir, tmp_path):
    """The same through the FMUs (gear-shaft FMU + four linear bearing FMUs)."""
    r = run_here(module="tests.probes.run_report",
                 args=["fmu_report", {"out_dir": tmp_path, "fmu_dir": fmu_dir}])
    assert r["mode"] == "fmu" and r["steps"] == 256
    assert r["R"] == r["summary_R"] == r["max_mesh"] / static_load()
    assert r["ptp"] == r["ptp_data"]
    assert r["labels"] == ["pinion_shaft_1x", "gear_shaft_1x", "mesh_GMF", "mesh_2GMF",
                           "mesh_3GMF"]
    lines = np.array(r["lines"])
    assert (lines[:, :2] == -1.0).all() and (lines[:, 2:] > 0).all()
