"""Observed order of the time integration on the paper's case with and without the
refinements of ``gear_fmu.structure`` (consistent start, contact location); on a smooth
problem, against its exact solution, in ``test_newmark.py``.

The observed order is the least-squares slope of log(error) against log(dt) over a ladder of
time steps, the error taken against a run at a much finer step.
"""


import math

import numpy as np
import pytest

from fmu_src import description
from fmu_src.case import load_case
from orchestrator.coupling.system import build_master


def observed_order(steps, errors) -> float:
    """Slope of log(error) against log(1 / steps)."""
    return float(np.polyfit(np.log(1.0 / np.asarray(steps, float)), np.log(errors), 1)[0])


def paper_case_state(n, refined, model, periods=2):
    """Journal positions [m] after ``periods`` mesh periods at ``n`` steps per period, with the
    coupled iterations converged to 1e-10."""
    case = load_case("baguet2010_spur", {
        "bearings.*.model": model, "simulation.tolerance": 1e-10,
        "simulation.steps_per_mesh_period": n, "simulation.consistent_start": refined,
        "simulation.locate_contact": refined})
    master = build_master(case, in_process=True)
    master.solve_static()
    master.exit_initialization()
    dt = description.time_step(case)
    for i in range(periods * n):
        master.step(i * dt, dt)
    return master.structure.journal_states()[:, :2].copy()


def paper_case_orders(model):
    """Observed orders with the refinements off and on. The ladder starts at 128 steps per
    mesh period: the damped 4.4 kHz mesh mode then has 20 steps per period and the errors are
    in the asymptotic range (from 64 with hybrid bearings they are not yet: order 1.76 over
    64-512, 2.0 over 128-512)."""
    steps = [128, 256, 512]
    out = {}
    for refined in (False, True):
        ref = paper_case_state(2048, refined, model)
        errors = [np.abs(paper_case_state(n, refined, model) - ref).max() for n in steps]
        out[refined] = observed_order(steps, errors)
        print(f"\npaper's case ({model} bearings), refinements {'on' if refined else 'off'}: "
              f"journal errors {', '.join(f'{e:.2e}' for e in errors)} m at "
              f"{', '.join(map(str, steps))} steps per mesh period: observed order "
              f"{out[refined]:.2f}")
    return out


def test_paper_case_order_with_and_without_contact_location():
    """Linear bearings (the paper's Sec. 3.3 model; fast): refinements off, the contact jumps
    inside steps and the zero start acceleration make the order about 1; on, 2."""
    orders = paper_case_orders("linear")
    assert 1.8 <= orders[True] <= 2.2  # measured 1.93
    assert orders[False] <= 1.6  # measured 0.94


@pytest.mark.slow
def test_paper_case_order_hybrid_bearings():
    """The paper's case itself (hybrid bearings): order 2 with the refinements. Without them
    the error of a step depends on where the contact exit falls inside it, which moves with
    the step size: the apparent order over a ladder is not a property of the scheme (measured
    1.85 here over 128-512, 0.93 with linear bearings), so it is printed, not asserted."""
    orders = paper_case_orders("hybrid")
    assert 1.8 <= orders[True] <= 2.2  # measured 2.00


@pytest.mark.parametrize("steps, warned", [(16, True), (64, False)])
def test_run_warns_when_newmark_lengthens_a_mesh_mode_period_over_1_percent(steps, warned,
                                                                            tmp_path):
    """At T/16 (f_mesh = 1345 Hz) the spur case's damped mesh mode near 4.4 kHz gets 4.9 steps
    per period: Newmark lengthens its period by 12 %; ``gsb run`` says so, names the field to
    raise and the value that brings the error under 1 %, and stores it. At T/64 (19.7 steps,
    0.8 %) it is silent. The shipped step T/32 is the paper's: a note, not a warning
    (tests/orchestrator/cli/test_run_startup.py)."""
    import warnings

    import h5py

    from orchestrator.run.checks import RunWarning, TimeStepWarning
    from orchestrator.run.runner import run_case

    case = load_case("baguet2010_spur", {"bearings.*.model": "linear",
                                         "simulation.steps_per_mesh_period": steps})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        s = run_case(case, steps=2, in_process=True, out_dir=tmp_path, progress=False)
    said = [w for w in caught if issubclass(w.category, RunWarning)]
    text = "\n".join(str(w.message) for w in said)
    with h5py.File(s.results) as f:
        stored = f.attrs["warnings"]
    assert s.notes == []
    if warned:
        assert said and all(w.category is TimeStepWarning for w in said)
        assert "the damped mesh mode at 43" in text
        assert "4.9 time steps per period" in text
        assert "lengthens its period by 12." in text
        assert "simulation.steps_per_mesh_period >= 59 (now 16)" in text
        assert "4.9 time steps per period" in str(stored)
    else:
        assert said == [] and str(stored) == ""


@pytest.mark.parametrize("helix", [0.0, 20.0])
def test_event_schedule_repeats_the_events_of_one_mesh_period(helix):
    """The structure's periodic event schedule equals the mesh's events computed directly over
    any interval (spur: 2 per mesh period, helical: one entry and one exit per slice)."""
    from fmu_src.examples import paper_structure
    from gear_fmu.step.events import ContactEvents

    st = paper_structure(helix)
    (mesh,) = st.meshes
    events = ContactEvents(mesh, lambda t: float(st.mesh_angles(st.input_angle(t))[0]))
    period = mesh.event_period
    rng = np.random.default_rng(3)
    for lo in rng.uniform(0.0, 500.0, 200):
        hi = lo + rng.uniform(0.0, 2.5) * period
        direct = mesh.event_angles(lo, hi)
        scheduled = np.array(events.between(lo, hi))
        assert scheduled.size == direct.size
        np.testing.assert_allclose(scheduled, direct, rtol=0, atol=1e-12)
    assert len(events.between(0.0, period)) == (2 if helix == 0.0 else 40)


@pytest.mark.parametrize("name", ["baguet2010_spur", "baguet2010_helical"])
def test_a_step_a_hair_off_the_mesh_periods_divisor(name):
    """The case's step as a tool user types it (8 significant digits, 1e-8 off T / 32) brings
    the contact events back towards the step's end by about 1e-8 of a step per step, so the
    located events cut ever so slightly short sub-steps. No sub-step is shorter than
    ``EVENT_SNAP`` dt: over 4 mesh periods with lumped bearings, the journals stay within
    5e-8 of the run at the exact step, relative to the largest displacement (measured 7.7e-9
    spur, 3.5e-9 helical: the step's own difference; with sub-steps down to 5e-7 dt the spur
    case's was 0.94)."""
    case = load_case(name, {"bearings.*.model": "lumped", "bearings.*.lumped_damping": 2000.0})
    dt = description.time_step(case)
    typed = float(f"{dt:.8g}")
    assert 0 < abs(typed / dt - 1) < 1e-7
    runs = []
    for h in (dt, typed):
        master = build_master(case, in_process=True)
        master.solve_static()
        master.exit_initialization()
        rows = []
        for i in range(4 * 32):
            rows.append(master.step(i * h, h).states[:, :2].copy())
        runs.append(np.array(rows))
    diff = float(np.abs(runs[1] - runs[0]).max() / np.abs(runs[0]).max())
    print(f"\n{name}: step {typed!r} s against {dt!r} s: largest journal difference {diff:.1e}")
    assert diff < 5e-8


def _counted_condensations(monkeypatch) -> list:
    """A list that grows by one entry per condensation the structure computes from now on
    (each new sub-step length's; clear it to count from a later point)."""
    import gear_fmu.structure

    made = []
    real = gear_fmu.structure.Condensation
    monkeypatch.setattr(gear_fmu.structure, "Condensation",
                        lambda *a, **k: made.append(1) or real(*a, **k))
    return made


def test_the_helical_case_condenses_each_recurring_sub_step_once(monkeypatch):
    """The helical case cuts most steps at contact events into sub-steps whose lengths recur
    every mesh period; each length's condensation (a factorisation of the 107 DOFs' step
    matrix) is computed once. A step starts at the structure's time, whose round-off drifts
    from k dt (2.4e-8 dt after 65,536 steps): with the cut fractions rounded to 2**-30 the
    lengths followed the drift, and 8192 steps condensed 117 lengths, not the 54 of one
    period's schedule."""
    made = _counted_condensations(monkeypatch)
    case = load_case("baguet2010_helical", {"bearings.*.model": "linear"})
    master = build_master(case, in_process=True)
    master.solve_static()
    master.exit_initialization()
    st, dt = master.structure.physics, description.time_step(case)
    schedule = {h for k in range(64) for h, *_ in st._pieces(dt, k * dt)}
    made.clear()
    k = 0
    while k < 8192:
        block = master.steps(k, dt, 128)
        assert block is not None and block.error is None
        k += block.count
    print(f"\nhelical case, 8192 steps: {len(made)} condensations, {len(schedule)} sub-step "
          "lengths in one mesh period's schedule")
    assert len(schedule) > 40  # the steps are cut
    assert len(made) <= len(schedule)


def _nanosecond_run(case, steps, monkeypatch):
    """Journal states, bearing forces, mesh force and TE of ``steps`` steps of the case's step
    rounded to whole nanoseconds (a libcosim host's clock: 5.1e-4 dt of event drift per mesh
    period), and how many sub-step lengths were condensed."""
    made = _counted_condensations(monkeypatch)
    h = round(description.time_step(case) * 1e9) * 1e-9
    master = build_master(case, in_process=True)
    try:
        master.solve_static()
        master.exit_initialization()
        made.clear()
        rows = []
        for k in range(steps):
            r = master.step(k * h, h)
            forces, errors, _ = master.structure.step_outputs()
            rows.append((r.states[:, :2].copy(), r.states[:, 2:].copy(),
                         np.array(r.bearing_force), forces[0], errors[0]))
    finally:
        master.close()
    return [np.array(channel) for channel in zip(*rows, strict=True)], len(made)


def test_a_step_that_does_not_recur_with_the_mesh_period_cuts_on_a_coarser_grain(monkeypatch):
    """A host's rounded step moves the contact events through the steps; with the cut
    fractions on the 2**-16 grain nearly every cut step was a new length to condense (0.55 ms
    each). On the 2**-10 grain (``gear_fmu.step.events.DRIFT_FRACTION``) the spur case
    condenses 9 lengths in 4 mesh periods against 15 (in 256: 276 against 1,019), and the
    run moves by 1.8e-2 of the golden run's tolerance (a tenth of what halving the step
    moves it; bound 5e-2). A step that recurs keeps the fine grain."""
    import gear_fmu.step.events as events
    from tests.golden import channel_tolerances, load_fixture

    case = load_case("baguet2010_spur")
    dt = description.time_step(case)
    cut = build_master(case, in_process=True)
    try:
        st = cut.structure.physics
        (mesh,) = st.meshes

        def pinion_angle(t):
            return float(st.mesh_angles(st.input_angle(t))[0])

        ev = events.ContactEvents(mesh, pinion_angle)
        angle = pinion_angle(dt) - pinion_angle(0.0)
        h = round(dt * 1e9) * 1e-9
        assert ev.fraction_grain(angle) == events.FRACTION
        assert ev.fraction_grain(angle * h / dt) == events.DRIFT_FRACTION
    finally:
        cut.close()
    coarse, n_coarse = _nanosecond_run(case, 128, monkeypatch)
    monkeypatch.setattr(events, "DRIFT_FRACTION", events.FRACTION)
    fine, n_fine = _nanosecond_run(case, 128, monkeypatch)
    golden = load_fixture()["runs"]["shipped"]
    tolerances = channel_tolerances(golden["64"], golden["32"])
    ratio = max(float((np.abs(a - b).reshape(128, -1).max(axis=0) / tolerances[name]).max())
                for name, a, b in zip(tolerances, coarse, fine, strict=True))
    print(f"\nspur case, 128 steps of dt rounded to 1 ns: {n_coarse} condensations on the "
          f"coarse grain, {n_fine} on the fine one; change / golden tolerance {ratio:.1e}")
    assert n_coarse <= 0.6 * n_fine
    assert ratio <= 5e-2


def two_stage_state(n, periods=2):
    """Journal positions [m] of the shipped two-stage reducer (linear bearings, contact
    located at the events of both meshes, the coupled iterations converged to 1e-10) after
    ``periods`` periods of its faster mesh at ``n`` steps per period."""
    case = load_case("two_stage_reducer", {
        "bearings.*.model": "linear", "simulation.tolerance": 1e-10,
        "simulation.steps_per_mesh_period": n})
    master = build_master(case, in_process=True)
    master.solve_static()
    master.exit_initialization()
    dt = description.time_step(case)
    i = 0
    while i < periods * n:
        block = master.steps(i, dt, periods * n - i)
        assert block.error is None, block.error
        i += block.count
    return master.structure.journal_states()[:, :2].copy()


@pytest.mark.slow
def test_two_stage_reducer_keeps_order_two():
    """The shipped two-stage reducer (a helical and a spur stage, the second's events not
    commensurate with the step; ``-m slow``, 30 s: tests/gear_fmu/test_train.py checks the
    order on two stages in the default run): order 2 once the steps resolve its helical
    stage. Its error against a run at 4096 steps per period of the faster mesh falls by 2^p
    from 256 to 512 steps with p = 1.93 measured (>= 1.8 asserted). Coarser ladders are not
    asymptotic yet, as on the paper's helical case alone (local orders 1.0, 1.4, 1.8, 2.0
    from 64 to 1024 steps; the two-stage case 1.2, 1.3, 1.9 from 64 to 512)."""
    ref = two_stage_state(4096)
    errors = [np.abs(two_stage_state(n) - ref).max() for n in (256, 512)]
    order = math.log2(errors[0] / errors[1])
    print(f"\ntwo-stage reducer: journal errors {errors[0]:.2e}, {errors[1]:.2e} m at 256, 512 "
          f"steps per mesh period: observed order {order:.2f}")
    assert order >= 1.8
