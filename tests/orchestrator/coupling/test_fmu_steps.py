"""The coupled step through the FMUs against the same step in-process: one definition of the
iteration (:mod:`orchestrator.coupling.step`), two transports, the same bits, counters and
errors.

Through the FMUs the structure is the gear-shaft FMU and each bearing its own bearing FMU
instance, called from compiled code (:mod:`orchestrator.coupling.fmi.steps`; force-only
groups called back in Python); in-process they are the physics objects' kernels
(:mod:`orchestrator.coupling.inprocess`). The two share nothing but the iteration and the
physics code the FMUs carry, so equal bits, counters and failures, step for step and in
blocks, check the FMU layer (the laws' packing, the native I/O, the state's save and restore,
the outputs' order) against the in-process transport: the paper's spur and helical cases with
hybrid, short, linear and lumped bearings, through the relaxation and the steps cut at contact
events, and a two-stage train whose six bearings use every registered model. (This module
compared the compiled loop through the FMUs with the master's Python loop, which no longer
exists: the in-process transport is the independent reference now.) The physics is asserted
elsewhere (the golden run, the monolithic Newton).
"""

from __future__ import annotations

import numpy as np
import pytest

from bearing_fmu.affine import AffineLaws
from bearing_fmu.base import BearingError
from fmu_src.case import load_case
from fmu_src.description import time_step
from orchestrator.coupling.fmi import FmuError
from orchestrator.coupling.master import NotConvergedError
from orchestrator.coupling.system import build_master
from tests.conftest import TRAIN_CASE
from tests.orchestrator.coupling.test_blocks import RUNOUT

#: the two-stage train with every registered bearing model (bearing_fmu.MODELS) at least once;
#: the lumped spring stiff enough for its 6.4 kN (1e8 N/m, the default, would put the journal
#: beyond its clearance)
MIXED = {"bearings.in_a.model": "hybrid", "bearings.in_b.model": "short",
         "bearings.mid_a.model": "fd", "bearings.mid_b.model": "linear",
         "bearings.out_a.model": "lumped", "bearings.out_a.lumped_stiffness": 1e9,
         "bearings.out_a.lumped_damping": 2e4, "bearings.out_b.model": "hybrid"}


def _pair(case, fmu_dir):
    """Two masters of ``case`` after the static solution, in-process and through the FMUs
    (of ``fmu_dir``); their static solutions are the same bits."""
    out = []
    for in_process in (True, False):
        m = build_master(case, in_process=in_process, fmu_dir=fmu_dir)
        out.append((m, m.solve_static()))
        m.exit_initialization()
    (a, sa), (b, sb) = out
    np.testing.assert_array_equal(sa.states, sb.states)
    np.testing.assert_array_equal(sa.bearing_force, sb.bearing_force)
    assert sa.iterations == sb.iterations
    return a, b


def _clock(m):
    """The structure's step count and time [s]: the in-process structure's own (the sum of
    its steps), the gear-shaft FMU's as its slave keeps it (the block's step times plus dt:
    the same to rounding, 1e-12 here; the FMU's own clock is the sum, as in-process)."""
    st = m.structure.physics or m.structure
    return st.n_steps, round(st.t, 12)


def _counters(m):
    return (m.total_iterations, m.total_bearing_evaluations, m.relaxed_steps,
            m.bearings.evaluations, *_clock(m))


def _same_state(a, b):
    np.testing.assert_array_equal(a.structure.journal_states(), b.structure.journal_states())
    for x, y in zip(a.structure.step_outputs(), b.structure.step_outputs(), strict=True):
        np.testing.assert_array_equal(x, y)
    for name in ("f0", "kb", "cb", "states", "force_at"):
        np.testing.assert_array_equal(getattr(a.laws, name), getattr(b.laws, name), name)
    assert _counters(a) == _counters(b)


def _same_blocks(a, b):
    assert a.error is None and b.error is None
    assert a.count == b.count and a.mismatch == b.mismatch
    for field in ("states", "bearing_force", "mesh_force", "transmission_error",
                  "gear_nodes", "iterations"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field), field)


def _close(*masters):
    for m in masters:
        m.close()


@pytest.mark.parametrize("name, model, steps, extra", [
    ("baguet2010_spur", "hybrid", 64, {}), ("baguet2010_helical", "hybrid", 24, {}),
    ("baguet2010_spur", "linear", 48, {}), ("baguet2010_helical", "lumped", 24, {}),
    ("baguet2010_spur", "short", 48, {}), ("baguet2010_spur", "hybrid", 24, RUNOUT)],
    ids=["spur-hybrid", "helical-hybrid", "spur-linear", "helical-lumped", "spur-short",
         "spur-runouts"])
def test_the_fmu_transport_gives_the_bits_of_the_in_process_one(name, model, steps, extra,
                                                                fmu_dir):
    """Step by step (a block of one each) for the first half, then one block for the rest:
    the reports, the rows, the laws, the counters and the structures' outputs (with gear
    runouts too, set through the gear-shaft FMU's parameters)."""
    case = load_case(name, {"bearings.*.model": model, **extra})
    in_process, fmu = _pair(case, fmu_dir)
    dt = time_step(case)
    try:
        half = steps // 2
        for i in range(half):
            ra, rb = in_process.step(i * dt, dt), fmu.step(i * dt, dt)
            assert (ra.iterations, ra.mismatch) == (rb.iterations, rb.mismatch), f"step {i + 1}"
            np.testing.assert_array_equal(ra.bearing_force, rb.bearing_force)
            np.testing.assert_array_equal(ra.states, rb.states)
        a, b = in_process.steps(half, dt, steps - half), fmu.steps(half, dt, steps - half)
        # the in-process structure plans its blocks by its condensation slots: take the rest
        rows = [a]
        while sum(r.count for r in rows) < steps - half:
            done = half + sum(r.count for r in rows)
            rows.append(in_process.steps(done, dt, steps - done))
        assert b.count == steps - half
        for field in ("states", "bearing_force", "mesh_force", "transmission_error",
                      "gear_nodes", "iterations"):
            np.testing.assert_array_equal(np.concatenate([getattr(r, field) for r in rows]),
                                          getattr(b, field), field)
        assert rows[-1].mismatch == b.mismatch
        _same_state(in_process, fmu)
    finally:
        _close(in_process, fmu)


def test_a_train_of_every_bearing_model_gives_the_same_bits_through_the_fmus(fmu_dir):
    """The two-stage reducer (three shafts, two meshes, six bearings) with hybrid, short, FD,
    linear and lumped bearings: through its own gear-shaft FMU and one bearing FMU instance
    per bearing, each of its own model and named after it, the static solution and four
    steps are the in-process transport's bits; the FD bearing's FMU (no compiled form) is
    called back in Python from the compiled step. The compiled step's arguments have the
    types the tests' warm-up compiles it for without an FMU
    (:func:`tests.probes.warm_up.other_transports`): the bearing slots of either transport
    those of no bearing, the FMU's structure arguments those of empty lists."""
    import numba

    from bearing_fmu import MODELS
    from fmu_src.contract import bearing_fmu_name
    from orchestrator.coupling.fmi.structure import block_arguments
    from orchestrator.coupling.step import bearing_slots

    case = load_case(TRAIN_CASE, MIXED)
    names = case.names("bearings")
    models = [case[f"bearings.{b}.model"] for b in names]
    assert set(models) == set(MODELS)
    in_process, fmu = _pair(case, fmu_dir)
    try:
        assert fmu.bearings.names == names
        assert [s.path.stem for s in fmu.bearings.slaves] == [bearing_fmu_name(m)
                                                              for m in models]
        assert fmu.structure.slave.path.stem.startswith("GearShaft_")
        assert (fmu.structure.n_meshes, fmu.structure.n_gears) == (2, 4)
        dt = time_step(case)
        a, b = in_process.steps(0, dt, 4), fmu.steps(0, dt, 4)
        _same_blocks(a, b)
        assert b.mesh_force.shape == (4, 2) and b.gear_nodes.shape == (4, 4, 2)
        assert b.states.shape == (4, 6, 4)
        _same_state(in_process, fmu)
        none = numba.typeof(bearing_slots(()))
        for m in (in_process, fmu):
            assert numba.typeof(bearing_slots(m.bearings.compiled_groups())) == none
        t = fmu.structure.t
        args, _, finish = fmu.structure.compiled_block(t, dt, 1, lambda k: t + k * dt)
        finish(0)
        assert numba.typeof(args) == numba.typeof(
            block_arguments([], [], [], [], [], [], [], [], 0.0))
    finally:
        _close(in_process, fmu)


def test_the_relaxed_step_at_300_rad_s_gives_the_same_bits(fmu_dir):
    """Step 408 at 300 rad/s puts Newton into a two-cycle and is relaxed (test_master): its
    laws (given by f0 alone) go to the gear-shaft FMU as the in-process structure takes them."""
    case = load_case("baguet2010_spur").with_overrides({"drive.speed": 300.0})
    in_process, fmu = _pair(case, fmu_dir)
    dt = time_step(case)
    n = 13 * 32
    try:
        rows = {"a": [], "b": []}
        for key, m in (("a", in_process), ("b", fmu)):
            done = 0
            while done < n:
                block = m.steps(done, dt, n - done)
                assert block.error is None
                rows[key].append(block)
                done += block.count
        for field in ("states", "iterations"):
            np.testing.assert_array_equal(
                np.concatenate([getattr(r, field) for r in rows["a"]]),
                np.concatenate([getattr(r, field) for r in rows["b"]]), field)
        _same_state(in_process, fmu)
        assert fmu.relaxed_steps >= 1
    finally:
        _close(in_process, fmu)


def _fail_both(case, change, fmu_dir, first_steps=2):
    """The error of the block after ``first_steps`` accepted steps of each transport, after
    ``change(master, dt)``: per transport (the error, its counters, the steps the block took)."""
    out = []
    masters = _pair(case, fmu_dir)
    try:
        for m in masters:
            step = time_step(case)
            block = m.steps(0, step, first_steps)
            assert block.error is None and block.count == first_steps
            dt_fail = change(m, step) or step
            block = m.steps_from(first_steps * step, dt_fail, 4)
            assert block.error is not None
            out.append((block.error, _counters(m), block.count))
    finally:
        _close(*masters)
    return out


def test_a_step_that_does_not_converge_fails_alike(fmu_dir):
    """Four iterations allowed, a tolerance none meets: the same error, after the same
    iterations and evaluations."""
    def never(m, dt):
        m.tol, m.max_iterations = 0.0, 4

    (ea, ca, na), (eb, cb, nb) = _fail_both(load_case("baguet2010_spur"), never, fmu_dir)
    assert type(ea) is type(eb) is NotConvergedError and str(ea) == str(eb)
    assert "did not converge in 4 iterations" in str(ea)
    assert ca == cb and na == nb == 0


def _push(first: int):
    """Laws that throw the journals of the bearings from index ``first`` on out of their
    clearance."""
    def change(m, dt):
        laws = m.laws
        f0 = laws.f0.copy()
        f0[first:] += 1e7
        m.laws = AffineLaws(f0, laws.kb, laws.cb)
    return change


@pytest.mark.parametrize("name, model, first, bearing", [
    ("baguet2010_spur", "hybrid", 2, "3"), ("baguet2010_spur", "short", 2, "3"),
    (TRAIN_CASE, "hybrid", 2, "mid_a")])
def test_a_failing_bearing_fails_at_the_same_bearing_and_state(name, model, first, bearing,
                                                              fmu_dir):
    """The first bearing out of its clearance: in-process the model's error, through the
    FMUs its FMU's (fmi2GetReal refused, its log), both naming the bearing by its name
    (``bearing``) and index (``bearing_index``) at the same journal state, after the same
    counters."""
    case = load_case(name, {"bearings.*.model": model})
    (ea, ca, na), (eb, cb, nb) = _fail_both(case, _push(first), fmu_dir)
    assert isinstance(ea, BearingError) and isinstance(eb, FmuError)
    assert not isinstance(eb, BearingError)
    assert ea.bearing == eb.bearing == bearing and ea.bearing_index == eb.bearing_index == first
    np.testing.assert_array_equal(ea.state, eb.state)
    assert str(eb).startswith(f"bearing {bearing} (Bearing{model.capitalize()}.fmu) failed at "
                              "state [")
    assert "fmi2GetReal returned" in str(eb)
    assert ca == cb and na == nb == 0


def test_a_refused_do_step_fails_with_the_fmu_log(fmu_dir):
    """A step of 200 mesh periods: the gear-shaft FMU discards it (MAX_STEP_MESH_PERIODS),
    at the block's first step, with its log (in-process steps have no such limit)."""
    case = load_case("baguet2010_spur")
    m = build_master(case, fmu_dir=fmu_dir)
    try:
        m.solve_static()
        m.exit_initialization()
        dt = time_step(case)
        assert m.steps(0, dt, 2).error is None
        block = m.steps_from(2 * dt, 200 * 32 * dt, 4)
        assert type(block.error) is FmuError and block.count == 0
        assert "doStep 3 from t = " in str(block.error) and "spans" in str(block.error)
        assert _clock(m)[0] == 2
    finally:
        m.close()
