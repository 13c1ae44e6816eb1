"""The master's steps through the FMUs in one compiled call
(:mod:`orchestrator.coupling.fmi.steps`) against the Python loop they replace
(:meth:`Master.step` without ``fused``, its FMI calls through ctypes): the same bits, counters
and errors, step for step and in blocks, spur and helical, hybrid, short, linear and lumped
bearing FMUs, through the relaxation and the steps cut at contact events. The physics is
asserted elsewhere (the FMU suites compare the FMU runs with in-process ones bit for bit, the
golden run, the monolithic Newton)."""

from __future__ import annotations

import numpy as np
import pytest

from bearing_fmu.affine import AffineLaws
from bearing_fmu.base import BearingError
from fmu_src.case import load_case
from fmu_src.description import time_step
from orchestrator.coupling.fmi import FmuError
from orchestrator.coupling.fmi import steps as steps_module
from orchestrator.coupling.master import CouplingError
from orchestrator.coupling.system import build_master


@pytest.fixture
def taken(monkeypatch):
    """The blocks the compiled loop took (None: left to the Python loop)."""
    out = []
    block = steps_module.FmuSteps._block
    monkeypatch.setattr(steps_module.FmuSteps, "_block",
                        lambda self, *a: out.append(block(self, *a)) or out[-1])
    return out


def _pair(case):
    """Two masters of ``case`` through the FMUs after the static solution: the compiled
    steps and the Python loop."""
    out = []
    for compiled in (True, False):
        m = build_master(case)
        assert isinstance(m.fused, steps_module.FmuSteps)
        if not compiled:
            m.fused = None
        m.solve_static()
        m.exit_initialization()
        out.append(m)
    return out


def _counters(m):
    return (m.total_iterations, m.total_bearing_evaluations, m.relaxed_steps,
            m.structure.n_steps, m.structure.t)


def _same_state(a, b):
    np.testing.assert_array_equal(a.structure.journal_states(), b.structure.journal_states())
    assert a.structure.outputs() == b.structure.outputs()
    for name in ("f0", "kb", "cb", "states", "force_at"):
        np.testing.assert_array_equal(getattr(a.laws, name), getattr(b.laws, name), name)
    assert _counters(a) == _counters(b)


def _close(*masters):
    for m in masters:
        m.close()


@pytest.mark.parametrize("name, model, steps", [("baguet2010_spur", "hybrid", 64),
                                                ("baguet2010_helical", "hybrid", 24),
                                                ("baguet2010_spur", "linear", 48),
                                                ("baguet2010_helical", "lumped", 24),
                                                ("baguet2010_spur", "short", 48)])
def test_the_compiled_steps_give_the_bits_of_the_python_loop(name, model, steps, taken):
    """Step by step (a block of one each) for the first half, then one block for the rest:
    the reports, the rows, the laws, the counters and the FMUs' outputs."""
    case = load_case(name, {"bearings.*.model": model})
    compiled, python = _pair(case)
    dt = time_step(case)
    try:
        half = steps // 2
        for i in range(half):
            rc, rp = compiled.step(i * dt, dt), python.step(i * dt, dt)
            assert (rc.iterations, rc.mismatch) == (rp.iterations, rp.mismatch), f"step {i + 1}"
            np.testing.assert_array_equal(rc.bearing_force, rp.bearing_force)
            np.testing.assert_array_equal(rc.states, rp.states)
        bc, bp = compiled.steps(half, dt, steps - half), python.steps(half, dt, steps - half)
        assert bc.error is None and bp.error is None
        assert bc.count == bp.count == steps - half and bc.mismatch == bp.mismatch
        for field in ("states", "bearing_force", "mesh_force", "transmission_error",
                      "gear_nodes", "iterations"):
            np.testing.assert_array_equal(getattr(bc, field), getattr(bp, field), field)
        _same_state(compiled, python)
        assert len(taken) == half + 1 and all(b is not None for b in taken)
    finally:
        _close(compiled, python)


def test_the_relaxed_step_at_300_rad_s_gives_the_same_bits(taken):
    """Step 408 at 300 rad/s puts Newton into a two-cycle and is relaxed (test_master): its
    laws (given by f0 alone) go to the gear-shaft FMU as the Python loop sends them."""
    case = load_case("baguet2010_spur").with_overrides({"drive.speed": 300.0})
    compiled, python = _pair(case)
    dt = time_step(case)
    try:
        bc, bp = compiled.steps(0, dt, 13 * 32), python.steps(0, dt, 13 * 32)
        assert bc.error is None and bp.error is None
        np.testing.assert_array_equal(bc.states, bp.states)
        np.testing.assert_array_equal(bc.iterations, bp.iterations)
        _same_state(compiled, python)
        assert compiled.relaxed_steps >= 1 and taken[0] is not None
    finally:
        _close(compiled, python)


def _fail_both(case, change, first_steps=2, dt=None):
    """The error of the block after ``first_steps`` accepted steps of each master, after
    ``change(master, dt)``: (type, message, counters, bearing), and the rows kept."""
    out = []
    masters = _pair(case)
    try:
        for m in masters:
            step = time_step(case)
            block = m.steps(0, step, first_steps)
            assert block.error is None
            dt_fail = change(m, step) or step
            block = m.steps_from(first_steps * step, dt_fail, 4)
            assert block.error is not None
            e = block.error
            out.append((type(e), str(e), _counters(m), getattr(e, "bearing", None),
                        block.count))
    finally:
        _close(*masters)
    return out


def test_a_step_that_does_not_converge_fails_alike(taken):
    def never(m, dt):
        m.tol, m.max_iterations = 0.0, 4

    compiled, python = _fail_both(load_case("baguet2010_spur"), never)
    assert compiled == python
    assert compiled[0] is CouplingError and "did not converge in 4 iterations" in compiled[1]
    assert all(b is not None for b in taken)


def _push_second_shaft(m, dt):
    """Laws that throw the journals of the second shaft out of their clearance."""
    laws = m.laws
    f0 = laws.f0.copy()
    f0[2:] += 1e7
    m.laws = AffineLaws(f0, laws.kb, laws.cb)


@pytest.mark.parametrize("model", ["hybrid", "short"])
def test_a_failing_bearing_fmu_fails_alike(model, taken):
    """Bearing 3 refuses its state (its FMU's fmi2GetReal returns an error): the same
    error, with the bearing, its state and the FMU's log, and the same counters."""
    case = load_case("baguet2010_spur", {"bearings.*.model": model})
    compiled, python = _fail_both(case, _push_second_shaft)
    assert compiled == python
    assert compiled[3] == 3 and "fmi2GetReal returned" in compiled[1]
    assert issubclass(compiled[0], FmuError) and not issubclass(compiled[0], BearingError)
    assert all(b is not None for b in taken)


def test_a_refused_do_step_fails_alike(taken):
    """A step of 200 mesh periods: the gear-shaft FMU discards it (MAX_STEP_MESH_PERIODS),
    at the block's first step, with its log."""
    case = load_case("baguet2010_spur")

    def long_step(m, dt):
        return 200 * 32 * dt

    compiled, python = _fail_both(case, long_step)
    assert compiled == python
    assert compiled[0] is FmuError and "doStep 3 from t = " in compiled[1]
    assert "spans" in compiled[1] and compiled[4] == 0
