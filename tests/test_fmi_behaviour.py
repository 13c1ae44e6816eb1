"""FMI 2.0 behaviour of every FMU, through fmpy as any FMI master would call it.

* a bad value is refused by the call that receives it (fmi2Error, the value and the limit in
  the log, the variable unchanged);
* an output that cannot be computed (a journal outside the clearance) makes the read return
  fmi2Error, never fmi2OK with NaN;
* bounds are declared in modelDescription.xml;
* fmi2GetFMUstate/SetFMUstate and Serialize/DeSerialize restore every FMU bit for bit, the
  bearing models' warm starts included, and a system checkpointed to bytes restarts in a new
  process exactly where it stopped;
* serialised states are numeric arrays (numpy reads them without pickle), and bytes that are
  not the FMU's own state (a pickle, another kind, an entry of the wrong shape) are refused
  with fmi2Error, the reason in the log, without running them and without losing the instance.

The FMUs load in the test's process (tests.helpers.run_here), but for the restart in a new
process.
"""

import zipfile
from xml.etree import ElementTree as ET

import pytest

from bearing_fmu import MODELS, fmu_name
from fmu_src.contract import BEARING_VARIABLES
from tests.helpers import run_here, run_isolated

BEARING_FMUS = [fmu_name(m) for m in MODELS]
#: models whose film has a clearance (the lumped spring has none: any state is valid)
FILM_MODELS = [m for m in MODELS if m != "lumped"]


@pytest.mark.parametrize("model", list(MODELS))
def test_bearing_fmus_refuse_bad_values_when_set(fmu_dir, model):
    out = run_here(f"""
        import json, math
        from fmpy.fmi1 import FMICallException
        from orchestrator.coupling.fmi import FmuInstance
        s = FmuInstance(r"{fmu_dir / (fmu_name(model) + '.fmu')}", "b")
        s.fmu.setupExperiment(startTime=0.0)
        s.fmu.enterInitializationMode()
        vr = s.vr
        r = {{}}
        for key, name, value in (("C", "C", -1e-4), ("mu", "mu", 0.0), ("nan", "s", math.nan),
                                 ("omega", "omega", -5.0)):
            since = len(s.messages)
            try:
                s.fmu.setReal([vr[name]], [value])
                r[key] = ["accepted"]
            except FMICallException as exc:
                r[key] = [exc.status, s.log_tail(since=since)]
        since = len(s.messages)
        try:
            s.fmu.setInteger([vr["rotation_sign"]], [0])
            r["sign"] = ["accepted"]
        except FMICallException as exc:
            r["sign"] = [exc.status, s.log_tail(since=since)]
        r["kept"] = [s.fmu.getReal([vr["C"]])[0], s.fmu.getReal([vr["mu"]])[0],
                     s.fmu.getInteger([vr["rotation_sign"]])[0]]
        s.close()
        print(json.dumps(r))
    """)
    assert out["C"][0] == 3 and "C = -0.0001 m refused: must be > 0 m" in out["C"][1]
    assert out["mu"][0] == 3 and "mu = 0.0 Pa.s refused: must be > 0 Pa.s" in out["mu"][1]
    assert out["nan"][0] == 3 and "s = nan m refused: not a finite number" in out["nan"][1]
    assert out["omega"][0] == 3 and "omega = -5.0 rad/s refused: must be > 0" in out["omega"][1]
    assert out["sign"][0] == 3 and "rotation_sign = 0 refused: must be one of 1, -1" \
        in out["sign"][1]
    start = {v.name: v.start for v in BEARING_VARIABLES}
    assert out["kept"] == [start["C"], start["mu"], start["rotation_sign"]]


@pytest.mark.parametrize("model", FILM_MODELS)
def test_a_journal_outside_the_clearance_fails_the_read_not_nan(fmu_dir, model):
    out = run_here(f"""
        import json
        from fmpy.fmi1 import FMICallException
        from orchestrator.coupling.fmi import FmuInstance
        s = FmuInstance(r"{fmu_dir / (fmu_name(model) + '.fmu')}", "b")
        s.fmu.setupExperiment(startTime=0.0)
        s.fmu.enterInitializationMode()
        vr = s.vr
        c = s.fmu.getReal([vr["C"]])[0]
        s.fmu.setReal([vr["s"], vr["t"]], [1.2 * c, 0.0])  # accepted: an input, not yet used
        since = len(s.messages)
        try:
            values = s.fmu.getReal([vr["F_s"], vr["K_ss"]])
            r = dict(status=0, values=values)
        except FMICallException as exc:
            r = dict(status=exc.status, log=s.log_tail(since=since))
        s.fmu.setReal([vr["s"]], [0.5 * c])  # back inside: the next read works
        r["after"] = s.fmu.getReal([vr["F_s"], vr["eccentricity"]])
        s.close()
        print(json.dumps(r))
    """)
    assert out["status"] == 3, out
    assert "eccentricity ratio 1.2" in out["log"] and "must be < 1" in out["log"]
    assert out["after"][1] == pytest.approx(0.5, abs=1e-15)


def test_bounds_are_declared_in_the_model_description(fmu_dir):
    with zipfile.ZipFile(fmu_dir / "BearingHybrid.fmu") as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    typed = {sv.get("name"): next(iter(sv)) for sv in root.iter("ScalarVariable")}
    assert typed["C"].get("min") == "0.0" and typed["mu"].get("min") == "0.0"
    assert typed["nodes"].get("min") == "8" and typed["omega"].get("min") == "0.0"
    assert typed["s"].get("min") is None  # an input any real value may take
    with zipfile.ZipFile(fmu_dir / "GearShaft.fmu") as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    typed = {sv.get("name"): next(iter(sv)) for sv in root.iter("ScalarVariable")}
    assert typed["gear_pair.pressure_angle"].get("max") == "0.7"
    assert typed["gear_pair.teeth[2]"].get("min") == "5"


@pytest.mark.parametrize("model", list(MODELS))
def test_bearing_fmu_state_round_trip_is_bit_exact(fmu_dir, model):
    """A saved state, restored after evaluations that moved the warm start elsewhere, gives
    the same outputs to the last bit as the first time; so does a serialised one."""
    out = run_here(f"""
        import json
        from orchestrator.coupling.fmi import FmuInstance
        s = FmuInstance(r"{fmu_dir / (fmu_name(model) + '.fmu')}", "b")
        f, vr = s.fmu, s.vr
        f.setupExperiment(startTime=0.0)
        f.enterInitializationMode()
        f.setReal([vr["omega"]], [325.0])
        outs = [vr[n] for n in ("F_s", "F_t", "K_ss", "K_st", "K_ts", "K_tt", "C_ss", "C_st",
                                "C_ts", "C_tt")]
        c = f.getReal([vr["C"]])[0]
        ins = [vr[n] for n in ("s", "t", "s_dot", "t_dot")]
        def at(x):
            f.setReal(ins, x)
            return f.getReal(outs)
        at([0.5 * c, -0.3 * c, 0.0, 0.0])
        f.exitInitializationMode()
        at([0.55 * c, -0.3 * c, 1e-3, 0.0])  # the warm start now holds this solve
        state = f.getFMUstate()
        blob = f.serializeFMUstate(state)
        first = at([0.6 * c, -0.25 * c, 2e-3, -1e-3])
        for k in range(5):  # move the warm start far away
            at([-0.4 * c, 0.5 * c * (k + 1) / 5, -3e-3, 2e-3])
        f.setFMUstate(state)
        again = at([0.6 * c, -0.25 * c, 2e-3, -1e-3])
        at([-0.4 * c, 0.5 * c, -3e-3, 2e-3])
        back = f.deSerializeFMUstate(blob)
        f.setFMUstate(back)
        restored = at([0.6 * c, -0.25 * c, 2e-3, -1e-3])
        f.freeFMUstate(back)
        f.freeFMUstate(state)
        s.close()
        print(json.dumps(dict(same=first == again, serialised=first == restored)))
    """)
    assert out["same"] and out["serialised"]


def test_a_checkpointed_system_restarts_exactly_in_a_new_process(fmu_dir, tmp_path):
    """Process 1: static solution and 12 steps of the paper's case through the five FMUs,
    every FMU's state serialised to a file after step 6. Process 2: fresh instances restored
    from the file (and the master's laws) run steps 7-12: the same journal states, bit for
    bit."""
    common = f"""
        import json
        import numpy as np
        from fmu_src import description
        from fmu_src.case import load_case
        from orchestrator.run.runner import build_master
        case = load_case("baguet2010_spur")
        dt = description.time_step(case)
        m = build_master(case, fmu_dir=r"{fmu_dir}")
        fmus = [m.structure.slave.fmu] + [s.fmu for s in m.bearings.slaves]
        path = r"{tmp_path / 'checkpoint.npz'}"
    """
    first = run_isolated(common + """
        m.solve_static()
        m.exit_initialization()
        for k in range(6):
            m.step(k * dt, dt)
        blobs = []
        for f in fmus:
            st = f.getFMUstate()
            blobs.append(f.serializeFMUstate(st))
            f.freeFMUstate(st)
        np.savez(path, *[np.frombuffer(b, dtype=np.uint8) for b in blobs], f0=m.laws.f0,
                 kb=m.laws.kb, cb=m.laws.cb, states=m.laws.states, force_at=m.laws.force_at,
                 t=m.structure.t, n=m.structure.n_steps)
        for k in range(6, 12):
            m.step(k * dt, dt)
        x = m.structure.journal_states().tolist()
        m.close()
        print(json.dumps(dict(x=x)))
    """)
    second = run_isolated(common + """
        from bearing_fmu.affine import AffineLaws
        saved = np.load(path, allow_pickle=False)
        m.bearings.exit_initialization()
        m.structure.exit_initialization()
        for k, f in enumerate(fmus):
            st = f.deSerializeFMUstate(saved[f"arr_{k}"].tobytes())
            f.setFMUstate(st)
            f.freeFMUstate(st)
        m.laws = AffineLaws(*(saved[n] for n in ("f0", "kb", "cb", "states", "force_at")))
        m.structure.t, m.structure.n_steps = float(saved["t"]), int(saved["n"])
        for k in range(6, 12):
            m.step(k * dt, dt)
        x = m.structure.journal_states().tolist()
        m.close()
        print(json.dumps(dict(x=x)))
    """)
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
    out = run_here(f"""
        import io, json, pickle
        import numpy as np
        from fmpy.fmi1 import FMICallException
        from fmu_src.state_codec import encode
        from orchestrator.coupling.fmi import FmuInstance
        class WritesAFile:
            def __reduce__(self):
                return (open, (r"{marker}", "w"))
        s = FmuInstance(r"{fmu_dir / (fmu + '.fmu')}", "x")
        f, vr = s.fmu, s.vr
        f.setupExperiment(startTime=0.0)
        f.enterInitializationMode()
        gear = {fmu == "GearShaft"}
        if gear:
            names = ["s_1", "t_1", "s_dot_1", "mesh_force"]
        else:
            names = ["F_s", "F_t", "K_ss", "C_tt"]
            c = f.getReal([vr["C"]])[0]
            f.setReal([vr[n] for n in ("omega", "s", "t")], [325.0, 0.5 * c, -0.3 * c])
        outs = [vr[n] for n in names]
        f.getReal(outs)
        f.exitInitializationMode()
        if gear:
            f.doStep(0.0, 1e-5)
        else:
            f.setReal([vr["s"], vr["s_dot"]], [0.55 * c, 1e-3])
        saved = f.getReal(outs)
        state = f.getFMUstate()
        good = f.serializeFMUstate(state)
        f.freeFMUstate(state)
        with np.load(io.BytesIO(good), allow_pickle=False) as z:  # numpy reads it, no pickle
            arrays = {{n: z[n] for n in z.files}}
        kind = str(arrays.pop("__kind__"))
        arrays.pop("__format_version__")
        # an entry of another shape: one checked against the live structure or model when the
        # state is set (a scalar for memoryless models: checked when deserialised)
        vectors = [n for n in sorted(arrays) if n.startswith(("structure/x", "model/"))
                   and arrays[n].ndim == 1]
        big = vectors[0] if vectors else "values/D"
        other = arrays | {{big: np.zeros(3, arrays[big].dtype)}}
        r = {{"kind": kind, "refused": {{}}}}
        for name, blob in (("pickle", pickle.dumps(WritesAFile())), ("text", b"a state"),
                           ("kind", encode("gsb.other", {{"x": 1.0}})),
                           ("shape", encode(kind, other))):
            since = len(s.messages)
            stage = "fmi2DeSerializeFMUstate"
            try:
                st = f.deSerializeFMUstate(blob)
                stage = "fmi2SetFMUstate"
                try:
                    f.setFMUstate(st)
                    r["refused"][name] = ["accepted"]
                finally:
                    f.freeFMUstate(st)
            except FMICallException as exc:
                r["refused"][name] = [exc.status, s.log_tail(since=since), stage, big]
        st = f.deSerializeFMUstate(good)
        f.setFMUstate(st)
        f.freeFMUstate(st)
        r["again"] = f.getReal(outs) == saved
        s.close()
        print(json.dumps(r))
    """)
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
