"""Bearing FMUs: built by pythonfmu, valid for fmpy, equal to the in-process models.

The FMUs load in the test's process (the patched native layer keeps instances independent);
``fmpy simulate`` runs them in a fresh host process that must exit cleanly.
"""

import subprocess
import sys

import pytest

from bearing_fmu import MODELS
from fmu_src.contract import bearing_fmu_name
from tests.helpers import ROOT, run_here

BEARING_FMUS = [bearing_fmu_name(m) for m in MODELS]
PROBES = "tests.probes.bearing_fmus"


@pytest.mark.parametrize("name", BEARING_FMUS)
def test_fmu_passes_fmpy_validation(fmu_dir, name):
    from fmpy.validation import validate_fmu

    problems = validate_fmu(str(fmu_dir / f"{name}.fmu"))
    assert problems == []


def test_all_bearing_fmus_share_one_variable_list(fmu_dir):
    from fmpy import read_model_description

    lists = {}
    for name in BEARING_FMUS:
        md = read_model_description(str(fmu_dir / f"{name}.fmu"))
        lists[name] = [(v.name, v.causality, v.type, v.unit) for v in md.modelVariables]
        assert all(v.description for v in md.modelVariables)
    first = lists[BEARING_FMUS[0]]
    assert all(vl == first for vl in lists.values())
    units = {n: u for n, _, _, u in first}
    assert units["F_s"] == "N" and units["K_st"] == "N/m" and units["C_tt"] == "N.s/m"


@pytest.mark.parametrize("model", list(MODELS))
def test_fmu_equals_in_process_model_in_global_frame(fmu_dir, model):
    """Every model, in a turned and mirrored frame, with non-default options, along a sequence
    of states (the warm starts): the FMU gives the in-process model's force, Kb and Cb bit for
    bit (the linear model before its freeze: its film)."""
    import numpy as np

    from bearing_fmu import BearingData, model_class
    from bearing_fmu.frames import LocalFrame
    from orchestrator.coupling.fmi import FmuBearings
    from orchestrator.coupling.inprocess import ModelBearings

    b = BearingData(0.09, 0.065, 110e-6, 0.0288)
    options = dict(nodes=96, axial_intervals=16, lumped_stiffness=3e8, lumped_damping=2e3)
    cls = model_class(model)
    mine = {o.key: options[o.key] for o in cls.options}
    params = dict(D=0.09, L=0.065, C=110e-6, mu=0.0288, frame_angle=0.3, rotation_sign=-1,
                  **options)
    ref = ModelBearings([cls.from_parameters(b, **mine)], [LocalFrame(0.3, -1)], [54.0])
    fmu = FmuBearings([fmu_dir / (bearing_fmu_name(model) + ".fmu")], [params], [54.0])
    try:
        for k in range(3):
            states = np.array([[40e-6 + 2e-6 * k, -30e-6, 1e-3, -2e-3 * k]])
            for a, c in zip(ref.evaluate(states), fmu.evaluate(states), strict=True):
                np.testing.assert_array_equal(c, a)
    finally:
        fmu.close()


@pytest.mark.parametrize("model", list(MODELS))
def test_the_hybrid_law_is_served_without_python_with_the_same_bits(fmu_dir, model):
    """The master's set of the journal state and read of the law (FmuBearings.evaluate) along
    7 evaluations, one of which fails for the film models (a journal outside the clearance),
    and for the hybrid model an eighth, a squeeze velocity its solver cannot converge at (it
    then starts cold): after each, the FMU gives
    the in-process model's outputs bit for bit; each failure is an error with its reason; and
    n_solves counts the evaluations that succeeded. For the hybrid model the patched library
    serves the calls with the compiled law once the slave has evaluated it: the slave's Python
    sees the first evaluation, each failure (to raise and log it) and the evaluation after it
    (which arms the library again): 3 sets and 5 reads of the 16 calls. The other models have
    no compiled law: Python serves all 14. The same after fmi2Reset."""
    out = run_here(module=PROBES, args=["native_law", {
        "fmu": fmu_dir / (bearing_fmu_name(model) + ".fmu"), "model": model}])
    assert out["same"] == [True] * 6, out
    errors = out["errors"]
    if model != "lumped":  # a spring: any state is valid
        assert "eccentricity ratio 1.2" in errors["outside"], errors
    if model == "hybrid":
        assert "did not converge" in errors["fast"], errors
    assert out["n_solves"] == 6 + sum(e is None for e in errors.values()), out
    expected = dict(set_real=3, get_real=5) if model == "hybrid" else dict(set_real=7,
                                                                           get_real=7)
    assert out["calls"] == expected
    # a journal state that is not finite is refused by fmi2SetReal, with the slave's message
    assert "fmi2SetReal returned error" in out["nan"] and "not a finite number" in out["nan"]
    assert out["same_after_nan"]
    # after fmi2Reset (a new slave) the same again: the library asks the new slave for its
    # buffer; it serves the calls once the slave has evaluated the law (2 of 6 in Python)
    assert out["after_reset"] == [True] * 3, out
    assert out["calls_after_reset"] == (dict(set_real=1, get_real=1) if model == "hybrid"
                                        else dict(set_real=3, get_real=3))


def test_a_hybrid_fmu_without_its_compiled_law_says_so_and_serves_in_python(fmu_dir):
    """If the compiled law cannot be loaded (an unimportable module here), the hybrid FMU
    logs a warning saying so and why, once per instance, and its Python serves every call
    with the same bits."""
    out = run_here(module=PROBES, args=["native_law", {
        "fmu": fmu_dir / "BearingHybrid.fmu", "model": "hybrid", "without_compiled_law": True}])
    assert out["same"] == [True] * 6 and out["after_reset"] == [True] * 3, out
    assert out["calls"] == dict(set_real=8, get_real=8), out["calls"]
    warnings = [m for m in out["log"] if "the compiled law cannot be loaded" in m]
    assert len(warnings) == 1 and warnings[0].startswith("[warning]"), out["log"]
    assert "ImportError" in warnings[0] or "ModuleNotFoundError" in warnings[0], warnings


def test_fmu_error_is_reported_not_fatal_and_state_round_trips(fmu_dir):
    out = run_here(module=PROBES, args=["error_and_state_round_trip",
                                        {"fmu": fmu_dir / "BearingShort.fmu"}])
    assert out["msg"] is not None and "eccentricity ratio 1.33333" in out["msg"]
    assert out["same"]


def test_linear_fmu_freezes_at_initialisation_exit(fmu_dir):
    """Hybrid until initialisation ends, then exactly affine with the coefficients at X0."""
    out = run_here(module=PROBES, args=["linear_freeze", {"fmu": fmu_dir / "BearingLinear.fmu"}])
    assert out["affine"] < 1e-13  # an affine law, to round-off
    assert out["at_x0"] < 1e-7 and out["k"] < 1e-4  # the hybrid's own tolerance at X0
    assert out["same_k"]


def test_fmpy_simulate_from_a_fresh_process(fmu_dir, tmp_path):
    """``fmpy simulate`` (the command a system engineer would run) exits cleanly, twice over."""
    out = tmp_path / "out.csv"
    for _ in range(3):
        proc = subprocess.run(
            [sys.executable, "-m", "fmpy", "simulate", str(fmu_dir / "BearingShort.fmu"),
             "--stop-time", "0.01", "--output-interval", "0.005", "--output-file", str(out)],
            capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, f"exit code {proc.returncode}: {proc.stderr[-2000:]}"
    header = out.read_text().splitlines()[0]
    assert "F_s" in header and "K_tt" in header


def test_many_instances_of_one_fmu_in_one_process(fmu_dir):
    out = run_here(module=PROBES, args=["many_instances", {"fmu": fmu_dir / "BearingShort.fmu"}])
    assert out["same"]


def test_variable_docs_are_generated_from_the_contract():
    from fmu_src.build.variables_doc import document

    doc = ROOT / "docs" / "fmu-variables.md"
    assert doc.read_text() == document(), \
        "run: python -m fmu_src.build.variables_doc > docs/fmu-variables.md"


def test_unit_definitions_come_from_the_unit_table(fmu_dir):
    """FMI 2.0 BaseUnit exponents from fmu_src.units: rad and rad/s carry rad="1"."""
    import zipfile
    from xml.etree import ElementTree as ET

    from fmu_src.units import DIMENSIONS

    with zipfile.ZipFile(fmu_dir / "BearingHybrid.fmu") as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    units = {u.get("name"): dict(u.find("BaseUnit").attrib) for u in root.iter("Unit")}
    assert units["rad/s"] == {"rad": "1", "s": "-1"}
    assert units["rad"] == {"rad": "1"}
    assert units["N.s/m"] == {"kg": "1", "s": "-1"}
    by_symbol = {d.symbol: d for d in DIMENSIONS.values()}
    for name, base in units.items():
        assert base == {k: str(v) for k, v in by_symbol[name].base.items()}, name
