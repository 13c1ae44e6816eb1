"""The transmission FMU (``gsb export-fmu``): the whole system, master inside, in FMI hosts.

What it must give is ``gsb run``'s answer at the same step: the tests compare its outputs,
read by a host in a fresh interpreter (the FMU runs the code it carries), with the in-process
run of the same case (``orchestrator.simulate``) for every registered bearing model, spur and
helical; through fmpy's one-call ``simulate_fmu`` (its own step arithmetic: the case's step
to the rounding of its clock, taken as the case's step); at a
whole-nanosecond step (libcosim's) and at a multiple of the case's step (cut into equal
internal steps); across a state saved, restored and serialised into another instance; and at
a step no bearing can carry (statuses). ecos, a C++ host without Python, runs it in
tests/system/test_ecos.py.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from bearing_fmu import MODELS
from tests.helpers import run_isolated
from tests.probes.transmission import OUTPUTS

CASE = "baguet2010_spur"
STEPS = 32  # one mesh period of the paper's case


def _case(name=CASE, **fields):
    from fmu_src.case import load_case

    return load_case(name).with_overrides(fields) if fields else load_case(name)


def _dt(case) -> float:
    from fmu_src.description import time_step

    return time_step(case)


def gsb_run_rows(case, steps: int) -> np.ndarray:
    """(steps, 26) ``gsb run``'s channels of the paper's case in the order of the probe's
    outputs: per bearing (s, t, s_dot, t_dot), the film forces, the mesh force and the
    transmission error."""
    import orchestrator as gsb

    r = gsb.simulate(case, in_process=True, steps=steps, progress=False)
    journals = np.concatenate([r["journal_position"], r["journal_velocity"]], axis=2)
    return np.hstack([journals.reshape(steps, 16), r["bearing_force"].reshape(steps, 8),
                      r["mesh_force"].reshape(steps, -1),
                      r["transmission_error"].reshape(steps, -1)])


def master_rows(case, h, steps: int, speeds=None) -> np.ndarray:
    """The same rows (of any train: per bearing its journal state and film force, per mesh
    its force and transmission error) from the master of ``gsb run`` stepping at ``h`` (not
    necessarily the case's step), X0 first; ``h`` one step [s] for all, or a sequence of
    ``steps`` steps (a host's clock that rounds its own time, as libcosim's, gives steps
    differing in their last bits). ``speeds``: the input speed at the end of each step,
    followed as the transmission FMU follows its input ``speed``
    (:meth:`gear_fmu.structure.Structure.follow_speed` to the end of the step)."""
    hs = [float(h)] * steps if np.ndim(h) == 0 else [float(x) for x in h]
    assert len(hs) == steps, (len(hs), steps)
    from orchestrator.coupling.system import build_master

    master = build_master(case, in_process=True)
    report = master.solve_static()
    master.exit_initialization()
    s = master.structure
    rows = []
    for k in range(steps + 1):
        if k:
            if speeds is not None:
                s.physics.follow_speed(s.physics.t + hs[k - 1], speeds[k - 1])
            report = master.step(s.physics.t, hs[k - 1])
        force, errors, _ = s.step_outputs()
        rows.append([*report.states.ravel(), *report.bearing_force.ravel(), *force, *errors])
    if speeds is not None and steps:
        assert s.physics.input_speed_at(s.physics.t) == speeds[-1]  # the ramps were followed
    master.close()
    return np.array(rows)


def _relative(a, b) -> float:
    """Largest difference of each output over its largest magnitude, over all outputs."""
    a, b = np.asarray(a), np.asarray(b)
    scale = np.maximum(np.abs(b).max(axis=0), 1e-300)
    return float((np.abs(a - b) / scale).max())


#: the FMU in a fresh interpreter against gsb run in the test's process, each output over its
#: largest magnitude: the same bits. (Before the computations ran on one BLAS thread,
#: bearing_fmu.blas_threads, a probe started after a test's Dask sweep ran its BLAS on one
#: thread, the test's process on two, and they differed by up to 3.3e-9.)
SAME_RUN = 0.0


def assert_same_run(rows, ref, what: str) -> None:
    diff = _relative(rows, ref)
    print(f"\n{what}: largest relative difference to gsb run {diff:.1e}")
    assert np.shape(rows) == np.shape(ref) and diff <= SAME_RUN, (what, diff)


def test_the_fmu_declares_the_case():
    """Not built: the variables it would declare carry the case (the FMU's checks below run
    what was built)."""
    from fmu_src.contract import transmission_variables

    case = _case()
    by_name = {v.name: v for v in transmission_variables(case)}
    assert by_name["torque"].causality == "input" and by_name["torque"].unit == "N.m"
    assert by_name["torque"].start == case["drive.torque"]
    assert by_name["bearings.'1'.model"].choices == tuple(MODELS)
    assert by_name["gears.gear.teeth"].start == case["gears.gear.teeth"]
    assert "simulation.mesh_periods" not in by_name  # the host's stop time decides
    assert [n for n in OUTPUTS if by_name[n].causality != "output"] == []


def test_fmpy_validates_it_and_it_carries_the_case_step(transmission_fmu):
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(transmission_fmu)) == []
    md = read_model_description(str(transmission_fmu))
    case = _case()
    assert float(md.defaultExperiment.stepSize) == _dt(case)
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate


def test_every_bearing_model_gives_gsb_runs_numbers(transmission_fmu):
    """In a fresh interpreter, one instance per registered model (``bearings.model`` set as a
    parameter) stepping at the case's step: ``gsb run`` of that model (:data:`SAME_RUN`)."""
    case = _case()
    h = _dt(case)
    runs = [{"start_values": {f"bearings.'{b}'.model": m for b in case.names("bearings")},
             "h": h, "n": STEPS} for m in MODELS]
    got = run_isolated(module="tests.probes.transmission",
                       args=["run", {"fmu": str(transmission_fmu), "runs": runs}])
    for model, out in zip(MODELS, got, strict=True):
        ref = gsb_run_rows(_case(**{"bearings.*.model": model}), STEPS)
        assert_same_run(out["rows"][1:], ref, model)
        assert out["steps"] == STEPS


def test_helical_gives_gsb_runs_numbers(helical_transmission_fmu):
    case = _case("baguet2010_helical")
    got = run_isolated(module="tests.probes.transmission",
                       args=["run", {"fmu": str(helical_transmission_fmu),
                                     "runs": [{"h": _dt(case), "n": 16}]}])
    assert_same_run(got[0]["rows"][1:], gsb_run_rows(case, 16), "helical")


def test_a_host_clock_of_the_case_step_is_the_case_step():
    """fmpy steps to ``t_k = k * output_interval``, so its steps ``t_(k+1) - t_k`` differ from
    the case's step in their last bits (by up to 15 ulps of dt within one mesh period, up to
    2 ulps of ``t_(k+1)`` anywhere: :func:`~orchestrator.coupling.transmission.is_case_step`):
    over the paper's 65,536 steps, from start times 0 and 0.1 s, every one is the case's step;
    libcosim's whole nanoseconds (23,236 or 23,237 ns) are not, nor is a step one part in 1e9
    off, even at a time of 1 s."""
    from orchestrator.coupling.transmission import is_case_step

    dt = _dt(_case())
    k = np.arange(65_537, dtype=np.float64)
    for start in (0.0, 0.1):
        t = start + k * dt
        steps = np.diff(t)
        assert (steps != dt).any()
        assert all(is_case_step(a, h, dt) for a, h in zip(t[:-1].tolist(), steps.tolist(),
                                                            strict=True))
    for t in (0.0, 1e-3, 1.0):
        for h in (23236e-9, 23237e-9, dt * (1 + 1e-9), dt * (1 - 1e-9)):
            assert not is_case_step(t, h, dt), (t, h)


def test_fmpys_simulate_fmu_gives_gsb_runs_bits(transmission_fmu):
    """fmpy's one call, in a fresh interpreter: its communication steps are ``t_(k+1) - t_k``
    with ``t_k = k * output_interval``, the case's step in all but their last bits, so the FMU
    takes them as the case's step (:func:`~orchestrator.coupling.transmission.is_case_step`)
    and its rows are ``gsb run``'s bit for bit (:data:`SAME_RUN`). Before, it took them as they
    came, and the rows differed from ``gsb run``'s by 4.7e-10 on one machine, 1.4e-9 on
    another (relative to each output's largest magnitude, on a journal velocity): a step's last
    bits changed where the master's and the structure's iterations stopped, and the
    trajectories parted from there; no bound on that follows from an argument short of the
    solvers' tolerances, so the difference is made zero instead. Three mesh periods: from the
    87th step on, fmpy's time ``k * dt`` and the structure's clock (the sum of k steps of dt,
    as in ``gsb run``) differ in their last bits, and the rows must still be ``gsb run``'s: the
    structure keeps its own clock, the FMU's time is the host's."""
    case = _case()
    dt = _dt(case)
    steps = 3 * STEPS
    clock = np.array(list(itertools.accumulate([dt] * steps)))  # as the structure adds them
    assert (clock != np.arange(1, steps + 1) * dt).any()  # the two clocks do part
    rows = np.array(run_isolated(module="tests.probes.transmission", args=[
        "simulate", {"fmu": str(transmission_fmu), "dt": dt, "steps": steps}]))
    assert len(rows) == steps
    assert_same_run(rows, gsb_run_rows(case, steps), "fmpy simulate_fmu")


def test_a_transmission_fmu_of_a_run_up_gives_gsb_runs_bits(tmp_path):
    """A run-up (325 -> 400 rad/s in 5 ms) exported as one FMU, its profile a parameter: fmpy's
    one call gives gsb run's rows bit for bit, as at a constant speed (the master inside
    follows the profile as gsb run's does; the time step is the highest speed's)."""
    from fmu_src.build.fmus import build_transmission_fmu

    case = _case(**{"drive.speed_profile": "ramp to 400 rad/s in 5 ms"})
    fmu = build_transmission_fmu(case, tmp_path)
    dt = _dt(case)
    steps = 10 * STEPS  # past the ramp's end (8.3 mesh periods at 400 rad/s)
    rows = np.array(run_isolated(module="tests.probes.transmission", args=[
        "simulate", {"fmu": str(fmu), "dt": dt, "steps": steps}]))
    assert steps * dt > 0.005
    assert_same_run(rows, gsb_run_rows(case, steps), "fmpy simulate_fmu, run-up")


def _stepped_run_up(steps: int, **fields):
    """A run-up 325 -> 400 rad/s driven step by step: the paper's case at a
    ``max_speed`` of 400 rad/s (time step dt, the 400 rad/s mesh's), the case with the same
    run-up as a profile (its table's points at the structure's clock, the sum of the steps:
    325 rad/s to step 53, 400 rad/s at step 265) and the speed at the end of each of ``steps``
    steps; the case with the other ``fields`` too."""
    from fmu_src.description import speed_profile

    dt = _dt(_case()) * (325.0 / 400.0)
    clock = [0.0, *itertools.accumulate([dt] * steps)]
    case = _case(**{"drive.speed_profile": f"table 0 s: 325 rad/s, {clock[53]!r} s: 325 rad/s,"
                                           f" {clock[265]!r} s: 400 rad/s", **fields})
    assert _dt(case) == dt
    profile = speed_profile(case)
    return case, dt, [profile.speed(t) for t in clock[1:]]


@pytest.mark.parametrize("gyroscopic", [False, True], ids=["", "gyroscopic"])
def test_a_host_drives_a_run_up_through_the_speed_input(transmission_fmu, gyroscopic):
    """The host sets the input ``speed`` before each step to the speed the run-up of
    :func:`_stepped_run_up` reaches at its end: in a fresh interpreter, the FMU's rows are
    ``gsb run``'s of that run-up as a profile to a tenth of what halving the time step changes
    (the same physics in another arithmetic: the angle summed step by step against the
    profile's closed form; measured 3.3e-8 against 0.27, each output's largest difference
    over its largest magnitude); with the gyroscopic terms too (their matrix at each step's
    speed, the host's or the profile's: 1.6e-8 against 0.27). A state saved in the ramp,
    set again and serialised into another instance, repeats the steps after it bit for bit."""
    steps = 320
    fields = {"simulation.gyroscopic": gyroscopic}
    case, dt, speeds = _stepped_run_up(steps, **fields)
    got = run_isolated(module="tests.probes.transmission", args=[
        "driven", {"fmu": str(transmission_fmu), "h": dt, "speeds": speeds,
                   "start_values": {"max_speed": 400.0, **fields}, "state_at": 150}])
    assert got["steps"] == steps
    ref = gsb_run_rows(case, steps)
    finer = _case(**{"drive.speed_profile": case["drive.speed_profile"],
                     "simulation.steps_per_mesh_period": 64, **fields})
    halving = _relative(gsb_run_rows(finer, 2 * steps)[1::2], ref)
    diff = _relative(got["rows"], ref)
    print(f"\ndriven by the host: {diff:.1e}; halving the step changes {halving:.1e}")
    assert diff <= 0.1 * halving
    assert got["again"] == got["restored"] == got["rows"][150:]


def test_a_speed_the_fmu_cannot_follow_is_refused_at_the_call(transmission_fmu):
    """``speed`` set after the initialisation: above ``max_speed`` (by default the case's
    speed), at 0, or changed for a case whose bearings are built for one speed, the setReal
    call returns fmi2Error and logs why (the value, the limit, what to change); the value is
    not taken (the next step runs). An unchanged speed with linear bearings is taken, and a
    changed one with the gyroscopic terms. In initialisation it is the parameter drive.speed:
    X0 at 350 rad/s."""
    linear = {f"bearings.'{b}'.model": "linear" for b in (1, 2, 3, 4)}
    cases = [{"speed": 400.0}, {"speed": 0.0},
             {"start_values": {**linear, "max_speed": 400.0}, "speed": 350.0},
             {"start_values": linear, "speed": 325.0},
             {"start_values": {"simulation.gyroscopic": True, "max_speed": 400.0},
              "speed": 350.0}]
    got = run_isolated(module="tests.probes.transmission", args=[
        "speed_refusals", {"fmu": str(transmission_fmu), "h": _dt(_case()), "cases": cases}])
    for case, expected in zip(got, [
            "speed = 400.0 rad/s refused: above max_speed = 325 rad/s, the highest speed the "
            "time step is sized for (set the parameter max_speed before initialisation)",
            "speed = 0.0 rad/s refused: must be > 0 rad/s",
            "speed = 350.0 rad/s refused: bearing 1 is linear, whose coefficients hold at one "
            "speed"], strict=False):
        assert "status 3 (error)" in case["status"] and expected in case["log"], case
        assert case["stepped"], case
    assert got[3:] == [{"status": "fmi2OK", "log": "", "stepped": True}] * 2
    as_input, as_parameter, paper = (
        run_isolated(module="tests.probes.transmission", args=[
            "run", {"fmu": str(transmission_fmu), "runs": [{"start_values": start, "h": 1e-5,
                                                            "n": 0}]}])[0]["rows"][0]
        for start in ({"speed": 350.0}, {"drive.speed": 350.0}, {}))
    assert as_input == as_parameter != paper


@pytest.mark.parametrize("nanoseconds", [math.floor, math.ceil])
def test_whole_nanosecond_steps(transmission_fmu, nanoseconds):
    """libcosim's steps are whole nanoseconds: 23,236 or 23,237 ns for the paper's
    23,236.6 ns, each taken as one internal step (within 1e-4 of the case's step), as the
    master of gsb run takes that step."""
    case = _case()
    h = nanoseconds(_dt(case) * 1e9) * 1e-9
    assert abs(h / _dt(case) - 1) < 1e-4
    got = run_isolated(module="tests.probes.transmission",
                       args=["run", {"fmu": str(transmission_fmu),
                                     "runs": [{"h": h, "n": STEPS}]}])[0]
    assert got["steps"] == STEPS
    assert_same_run(got["rows"], master_rows(case, h, STEPS), f"{h!r} s")


def test_a_longer_step_is_cut_into_equal_steps(transmission_fmu):
    """A communication step of 4 dt is 4 internal steps of dt: the rows of gsb run at every
    fourth step (4 dt / 4 is dt exactly); 3.5 dt is 4 steps of 0.875 dt."""
    from orchestrator.coupling.transmission import internal_steps

    case = _case()
    dt = _dt(case)
    assert internal_steps(4 * dt, dt) == 4 and internal_steps(3.5 * dt, dt) == 4
    assert internal_steps(dt * (1 + 0.9e-4), dt) == 1 and internal_steps(dt * 1.001, dt) == 2
    got = run_isolated(module="tests.probes.transmission",
                       args=["run", {"fmu": str(transmission_fmu),
                                     "runs": [{"h": 4 * dt, "n": STEPS // 4},
                                              {"h": 3.5 * dt, "n": 2}]}])
    assert got[0]["steps"] == STEPS
    assert_same_run(got[0]["rows"][1:], gsb_run_rows(case, STEPS)[3::4], "4 dt")
    assert got[1]["steps"] == 8
    assert_same_run([got[1]["rows"][2]], master_rows(case, 0.875 * dt, 8)[8:], "3.5 dt")


def test_states_round_trip_exactly(transmission_fmu):
    """A state saved after 5 steps: set again in the same instance, and serialised then
    deserialised into another instance (which first solves its own X0, as a resumed run
    does), the next 7 steps repeat the straight run's bits."""
    got = run_isolated(module="tests.probes.transmission",
                       args=["state_round_trip", {"fmu": str(transmission_fmu),
                                                  "h": _dt(_case()), "n": 12, "k": 5}])
    assert got["straight"] == got["again"] == got["restored"]
    assert np.isfinite(np.array(got["straight"])).all()


def test_a_step_no_bearing_can_carry(transmission_fmu):
    """A torque of 2e5 N m (900 times the paper's) drives the journals out of their
    clearances within a few steps: that doStep returns fmi2Discard, the next read fmi2Error,
    and no step is taken any more (fmi2Discard) until a state is set."""
    got = run_isolated(module="tests.probes.transmission",
                       args=["impossible_step", {"fmu": str(transmission_fmu),
                                                 "h": _dt(_case()), "torque": 2e5}])
    assert 0 < got["ok_steps"] < 50
    assert "status 2 (discard)" in got["doStep"]
    assert "status 3 (error)" in got["getReal"]
    assert "status 2 (discard)" in got["doStep again"]


def test_a_step_that_fails_inside_a_longer_communication_step(transmission_fmu):
    """The same torque with communication steps of 4 dt (4 internal steps each, taken in one
    compiled block): the doStep refused is the one holding the internal step that failed at
    dt (14 steps of dt taken, the 15th refused: the third of the fourth doStep of 4 dt), with
    the same statuses."""
    dt = _dt(_case())
    one, four = (run_isolated(module="tests.probes.transmission",
                              args=["impossible_step", {"fmu": str(transmission_fmu), "h": h,
                                                        "torque": 2e5}])
                 for h in (dt, 4 * dt))
    assert one["ok_steps"] % 4 > 0  # the failing step is inside a doStep of 4 dt
    assert four["ok_steps"] == one["ok_steps"] // 4
    for what, status in (("doStep", 2), ("getReal", 3), ("doStep again", 2)):
        assert f"status {status}" in four[what]


def test_a_bearing_fmu_of_your_own_carried_inside(fmu_dir, tmp_path):
    """``gsb export-fmu --bearing-fmu BearingLumped.fmu`` carries that FMU and runs the four
    bearings through it (fmpy inside the FMU): the bits of gsb run with the lumped model, which
    the bearing FMU computes as the in-process model does."""
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-m", "orchestrator.cli", "export-fmu", CASE,
                           "--bearing-fmu", str(fmu_dir / "BearingLumped.fmu"),
                           "--dest", str(tmp_path)], capture_output=True, text=True,
                          timeout=600, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    fmu = tmp_path / f"{CASE}.fmu"
    # the command its hint gives (the README's): fmpy at the case's step, 1,024 steps
    import shlex

    hint = shlex.split(proc.stdout.split("e.g. ", 1)[1].rsplit(")", 1)[0])
    assert hint[:4] == ["python", "-m", "fmpy", "simulate"] and hint[4] == str(fmu), hint
    assert float(hint[hint.index("--output-interval") + 1]) == _dt(_case())
    sim = subprocess.run([sys.executable, *hint[1:], "--output-file", str(tmp_path / "o.csv")],
                         capture_output=True, text=True, timeout=600, cwd=tmp_path)
    assert sim.returncode == 0, sim.stderr[-2000:]
    assert len((tmp_path / "o.csv").read_text().splitlines()) >= 1024
    missing = subprocess.run([sys.executable, "-m", "orchestrator.cli", "export-fmu", CASE,
                              "--bearing-fmu", str(tmp_path / "nowhere.fmu")],
                             capture_output=True, text=True, timeout=600, cwd=tmp_path)
    assert missing.returncode == 2 and "nowhere.fmu: no such file" in missing.stderr
    case = _case(**{"bearings.*.model": "lumped"})
    got = run_isolated(module="tests.probes.transmission",
                       args=["run", {"fmu": str(fmu), "runs": [{"h": _dt(case), "n": 8}]}])
    assert_same_run(got[0]["rows"][1:], gsb_run_rows(case, 8), "lumped through a bearing FMU")


def test_the_transmission_fmu_of_another_train(tmp_path):
    """``gsb export-fmu two_stage_reducer`` with bearings of three models: the FMU passes
    fmpy's validation, declares each of its six bearings' journal state and film force and
    each of its two meshes' outputs by name, and in a fresh interpreter gives the bits of the
    master of ``gsb run`` (in-process) at the case's step."""
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    from fmu_src.build.fmus import build_transmission_fmu
    from fmu_src.contract import transmission_output_names
    from tests.conftest import TRAIN_CASE
    from tests.probes.transmission import outputs_of

    case = _case(TRAIN_CASE)
    fmu = build_transmission_fmu(case, tmp_path)
    assert validate_fmu(str(fmu)) == []
    md = read_model_description(str(fmu))
    outputs = [v.name for v in md.modelVariables if v.causality == "output" and v.type == "Real"]
    assert outputs == transmission_output_names(case) == outputs_of(TRAIN_CASE)
    assert {"s_dot_mid_b", "F_t_out_a", "mesh_force_stage2",
            "transmission_error_stage1"} <= set(outputs)
    models = {"bearings.in_b.model": "short", "bearings.mid_b.model": "linear"}
    steps = 6
    got = run_isolated(module="tests.probes.transmission", args=[
        "run", {"fmu": str(fmu), "case": TRAIN_CASE, "runs": [{
            "start_values": models, "h": _dt(case), "n": steps}]}])[0]
    assert got["steps"] == steps
    ref = master_rows(case.with_overrides(models), _dt(case), steps)
    assert_same_run(got["rows"], ref, "two-stage reducer")
