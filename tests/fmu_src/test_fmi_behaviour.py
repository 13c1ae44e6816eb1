"""FMI 2.0 behaviour of every FMU, through fmpy as any FMI master would call it.

* a bad value is refused by the call that receives it (fmi2Error, the value and the limit in
  the log, the variable unchanged);
* an output that cannot be computed (a journal outside the clearance) makes the read return
  fmi2Error, never fmi2OK with NaN; a step that cannot be computed returns fmi2Discard from
  fmi2DoStep, the reason in the log;
* bounds are declared in modelDescription.xml as they are enforced;
* fmi2GetFMUstate/SetFMUstate and Serialize/DeSerialize restore every FMU bit for bit, the
  bearing models' warm starts included, and a system checkpointed to bytes restarts in a new
  process exactly where it stopped;
* serialised states are numeric arrays (numpy reads them without pickle), and bytes that are
  not the FMU's own state (a pickle, another kind, an entry of the wrong shape) are refused
  with fmi2Error, the reason in the log, without running them and without losing the instance.

The FMUs load in the test's process (tests.helpers.run_here), but for the restart in a new
process.
"""

import math
import zipfile
from xml.etree import ElementTree as ET

import pytest

from bearing_fmu import MODELS
from fmu_src.contract import bearing_fmu_name, bearing_variables
from tests.helpers import run_here, run_isolated

BEARING_FMUS = [bearing_fmu_name(m) for m in MODELS]
#: models whose film has a clearance (the lumped spring has none: any state is valid)
FILM_MODELS = [m for m in MODELS if m != "lumped"]
#: models that are a film model after the initialisation too (the linear model's frozen law is
#: affine, defined at any state, in process as in the FMU)
STEPPING_FILM_MODELS = [m for m in FILM_MODELS if m != "linear"]
PROBES = "tests.probes.fmi_behaviour"


def fmu_file(fmu_dir, model):
    return fmu_dir / (bearing_fmu_name(model) + ".fmu")


@pytest.mark.parametrize("model", list(MODELS))
def test_bearing_fmus_refuse_bad_values_when_set(fmu_dir, model):
    out = run_here(module=PROBES, args=["refuse_bad_values", {"fmu": fmu_file(fmu_dir, model)}])
    assert out["C"][0] == 3 and "C = -0.0001 m refused: must be > 0 m" in out["C"][1]
    assert out["mu"][0] == 3 and "mu = 0.0 Pa.s refused: must be > 0 Pa.s" in out["mu"][1]
    assert out["nan"][0] == 3 and "s = nan m refused: not a finite number" in out["nan"][1]
    assert out["omega"][0] == 3 and "omega = -5.0 rad/s refused: must be > 0" in out["omega"][1]
    assert out["sign"][0] == 3 and "rotation_sign = 0 refused: must be one of 1, -1" \
        in out["sign"][1]
    start = {v.name: v.start for v in bearing_variables()}
    assert out["kept"] == [start["C"], start["mu"], start["rotation_sign"]]


@pytest.mark.parametrize("model", FILM_MODELS)
def test_a_journal_outside_the_clearance_fails_the_read_not_nan(fmu_dir, model):
    out = run_here(module=PROBES, args=["read_outside_the_clearance",
                                        {"fmu": fmu_file(fmu_dir, model)}])
    assert out["status"] == 3, out
    assert "eccentricity ratio 1.2" in out["log"] and "must be < 1" in out["log"]
    assert out["after"][1] == pytest.approx(0.5, abs=1e-15)


def test_bounds_are_declared_in_the_model_description(fmu_dir):
    with zipfile.ZipFile(fmu_dir / "BearingHybrid.fmu") as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    typed = {sv.get("name"): next(iter(sv)) for sv in root.iter("ScalarVariable")}
    # > 0: the smallest positive double, the least value accepted (FMI has no strict bound)
    assert typed["C"].get("min") == "5e-324" and typed["mu"].get("min") == "5e-324"
    assert typed["nodes"].get("min") == "8" and typed["omega"].get("min") == "5e-324"
    assert typed["s"].get("min") is None  # an input any real value may take
    with zipfile.ZipFile(fmu_dir / "GearShaft.fmu") as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    typed = {sv.get("name"): next(iter(sv)) for sv in root.iter("ScalarVariable")}
    assert typed["gears.pinion.pressure_angle"].get("max") == "0.7"
    assert typed["gears.gear.teeth"].get("min") == "5"


@pytest.mark.parametrize("model", list(MODELS))
def test_bearing_fmu_state_round_trip_is_bit_exact(fmu_dir, model):
    """A saved state, restored after evaluations that moved the warm start elsewhere, gives
    the same outputs to the last bit as the first time; so does a serialised one."""
    out = run_here(module=PROBES, args=["state_round_trip", {"fmu": fmu_file(fmu_dir, model)}])
    assert out["same"] and out["serialised"]


def test_a_checkpointed_system_restarts_exactly_in_a_new_process(fmu_dir, tmp_path):
    """Process 1: static solution and 12 steps of the paper's case through the five FMUs,
    every FMU's state serialised to a file after step 6. Process 2: fresh instances restored
    from the file (and the master's laws) run steps 7-12: the same journal states, bit for
    bit."""
    where = {"fmu_dir": fmu_dir, "path": tmp_path / "checkpoint.npz"}
    first = run_isolated(module=PROBES, args=["checkpoint", {**where, "phase": "first"}])
    second = run_isolated(module=PROBES, args=["checkpoint", {**where, "phase": "second"}])
    assert second["x"] == first["x"]


@pytest.mark.parametrize("fmu", ["GearShaft", *BEARING_FMUS])
def test_bytes_that_are_not_the_fmus_own_state_are_refused_with_fmi2error(fmu_dir, fmu,
                                                                          tmp_path):
    """fmi2DeSerializeFMUstate of a pickle (one that would create a file when loaded), of
    text, of another kind of state: fmi2Error with the reason in the log, nothing loaded.
    A state of the FMU's own kind with an entry of the wrong shape: fmi2Error at
    fmi2SetFMUstate, where the entry is checked against the structure or the model (at
    fmi2DeSerializeFMUstate for a memoryless model's scalar). The instance lives on: its own
    state restores exactly afterwards."""
    marker = tmp_path / "marker"
    out = run_here(module=PROBES, args=["refuse_foreign_states", {
        "fmu": fmu_dir / (fmu + ".fmu"), "gear": fmu == "GearShaft", "marker": marker}])
    assert out["kind"] == ("gsb.gear_shaft_fmu_state" if fmu == "GearShaft"
                           else f"gsb.bearing_fmu_state.{fmu.removeprefix('Bearing').lower()}")
    refused = out["refused"]
    assert all(v[0] == 3 for v in refused.values()), refused  # fmi2Error, never fatal
    assert "StateFormatError: the serialised FMU state is a Python pickle" in refused["pickle"][1]
    assert "is not a saved state of this format" in refused["text"][1]
    assert f"is a 'gsb.other' state, not a '{out['kind']}' state" in refused["kind"][1]
    assert "has shape (3,), expected" in refused["shape"][1], refused["shape"]
    memoryless = fmu in ("BearingShort", "BearingLumped")
    assert refused["shape"][2] == ("fmi2DeSerializeFMUstate" if memoryless
                                   else "fmi2SetFMUstate"), refused["shape"]
    assert all(v[2] == "fmi2DeSerializeFMUstate" for k, v in refused.items() if k != "shape")
    assert not marker.exists()
    assert out["again"]


@pytest.mark.parametrize("model", list(MODELS))
def test_a_bearing_step_that_cannot_be_computed_is_not_ok(fmu_dir, model):
    """A fixed-step host (OMSimulator, ecos) sets the inputs, calls fmi2DoStep and reads the
    outputs: at inputs where the law cannot be computed (the journal outside the clearance; a
    state at which the law overflows) the doStep returns fmi2Discard with the reason in the log
    (the host learns it there, not from NaN outputs) and the read returns fmi2Error. Valid
    inputs step again."""
    out = run_here(module=PROBES, args=["bearing_step_that_cannot_be_computed", {
        "fmu": fmu_file(fmu_dir, model), "film": model in STEPPING_FILM_MODELS}])
    assert ("outside" in out) == (model in STEPPING_FILM_MODELS)
    for key in ("good", "again"):
        (status, log), (read, values) = out[key]
        assert status == 0 and read == 0 and math.isfinite(sum(values)), (key, out[key])
    reasons = {"overflow": "not finite", "outside": "eccentricity ratio 1.2"}
    for key in [k for k in reasons if k in out]:
        (status, log), (read, _), (read_one, _) = out[key]
        assert status == 2, (key, out[key])  # fmi2Discard
        assert any(m.startswith("[error]") and reasons[key] in m and "doStep" in m
                   for m in log), (key, log)
        assert read == 3 and read_one == 3, (key, out[key])  # fmi2Error


def test_a_gear_step_that_cannot_be_computed_is_not_ok(fmu_dir):
    """Laws that make the Newton iteration diverge, and a step of 1e6 s (answered at once,
    not after hours of contact events): fmi2Discard with the reason in the log, then the
    outputs read fmi2Error (the structure is not at a computed state) and further steps are
    refused until a saved state is restored; from it the step works."""
    out = run_here(module=PROBES, args=["gear_step_that_cannot_be_computed",
                                        {"fmu": fmu_dir / "GearShaft.fmu"}])
    for key in ("good", "again"):
        (status, _), (read, values) = out[key]
        assert status == 0 and read == 0 and math.isfinite(sum(values)), (key, out[key])
    (status, log), (read, values), (retry, retry_log) = out["diverging"]
    assert status == 2 and read == 3 and all(math.isnan(x) for x in values), out["diverging"]
    assert any("NewmarkConvergenceError" in m for m in log), log
    assert retry == 2 and any("earlier failure" in m for m in retry_log), retry_log
    (status, log), (read, _) = out["huge_dt"]
    assert status == 2 and read == 3, out["huge_dt"]
    assert any("dt = 1e+06 s" in m and "mesh periods" in m for m in log), log


@pytest.mark.parametrize("fmu", ["GearShaft", *BEARING_FMUS])
def test_declared_bounds_are_the_enforced_ones(fmu_dir, fmu):
    """Every parameter and input with a min or max in modelDescription.xml: the bound itself
    is accepted (fmi2OK) and the nearest value beyond it refused (fmi2Error). A strict bound
    (> 0) is declared as the smallest double above it, and its description says so."""
    from fmu_src.contract import gear_variables

    out = run_here(module=PROBES, args=["declared_bounds", {"fmu": fmu_dir / f"{fmu}.fmu"}])
    variables = bearing_variables() if fmu != "GearShaft" else gear_variables()
    exclusive = {v.name: v.minimum for v in variables if v.exclusive_minimum}
    bounded = {v.name for v in variables if v.causality in ("parameter", "input")
               and (v.minimum is not None or v.maximum is not None)}
    assert set(out) == bounded and set(exclusive) <= bounded
    for name, r in out.items():
        for value, at_bound, status in r["tries"]:
            assert status == (0 if at_bound else 3), (name, value, r)
        if name in exclusive:
            limit = exclusive[name]
            assert float(r["min"]) == math.nextafter(limit, math.inf), (name, r)
            assert r["description"].endswith(f"(> {limit:g})"), (name, r["description"])
