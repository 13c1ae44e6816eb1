"""Blocks of coupled steps in one compiled call (:meth:`Master.steps`,
:func:`orchestrator.coupling.fused.coupled_steps`) against the same steps one call each
(:meth:`Master.step`, itself checked against the Python loop in ``test_fused``): the same
bits, counters and errors, step for step, spur and helical, hybrid, short, linear and lumped
bearings, with gear runouts, through the relaxation (on two threads: ``test_fused``, the
module that compiles the threaded kernel); steps that the compiled loop does not take end a
block and take
:meth:`Master.step`. The physics of the step is asserted elsewhere (the
monolithic Newton, the golden run, the order); runs through the runner are compared with
runs through FMUs by the FMU suites. Slaves the compiled loop does not take (other bearing
models, FMUs) take blocks of the master's Python loop, which gather the steps' rows: the same
bits and errors as single steps too."""

from __future__ import annotations

import numpy as np
import pytest

from bearing_fmu.affine import AffineLaws
from bearing_fmu.base import BearingError
from fmu_src.case import load_case
from fmu_src.description import time_step
from gear_fmu.step.newmark import NewmarkConvergenceError
from orchestrator.coupling.master import CouplingError
from orchestrator.coupling.system import build_master
from tests.orchestrator.coupling.test_fused import _counters, _same_state
from tests.orchestrator.coupling.test_fused import _with_runout as with_runout

#: block length of these tests: short, so that blocks end at their length, at contact
#: events and at the end of the run
BLOCK = 7


def _masters(case, structure=None, threads=1):
    """Two masters of ``case`` after the static solution."""
    out = []
    for _ in range(2):
        m = build_master(case, in_process=True,
                         structure=None if structure is None else structure(case),
                         threads=threads)
        m.solve_static()
        m.exit_initialization()
        out.append(m)
    return out


def _step(m, i, dt):
    """Step i of dt through :meth:`Master.step`: ``([row], None)`` or ``([], its error)``; a
    row is (states, force, mesh force, TE, gear nodes, iterations)."""
    st = m.structure
    try:
        r = m.step(i * dt, dt)
    except Exception as exc:  # compared with the other master's
        return [], exc
    return [(r.states.copy(), r.bearing_force.copy(), st.mesh_force(),
             st.transmission_error(), st.gear_displacements().copy(), r.iterations)], None


def _rows_of_steps(m, dt, first, n):
    """Steps ``first`` .. ``n`` - 1 one call each: their rows, and the error that ended
    them (None)."""
    rows = []
    for i in range(first, n):
        row, error = _step(m, i, dt)
        rows += row
        if error is not None:
            return rows, error
    return rows, None


def _rows_of_blocks(m, dt, first, n, each=None):
    """The same through :meth:`Master.steps` (blocks of :data:`BLOCK`), ``each(i)`` after
    the steps before step i are taken, and how many steps blocks took and how many blocks had
    more than one step."""
    rows, in_blocks, long_blocks, i = [], 0, 0, first
    while i < n:
        block = m.steps(i, dt, min(BLOCK, n - i))
        if block is None:
            row, error = _step(m, i, dt)
            rows += row
            if error is not None:
                return rows, error, in_blocks, long_blocks
            i += 1
            continue
        for k in range(block.count):
            rows.append((block.states[k], block.bearing_force[k], block.mesh_force[k],
                         block.transmission_error[k], block.gear_nodes[k],
                         block.iterations[k]))
        in_blocks += block.count
        long_blocks += block.count > 1
        i += block.count
        if block.error is not None:
            return rows, block.error, in_blocks, long_blocks
        if each is not None:
            each(i)
    return rows, None, in_blocks, long_blocks


def _same_mesh_state(a, b):
    """The structures' mesh evaluations, every array and figure (the load along the face
    width of Fig. 13 included)."""
    ma, mb = a.structure.physics.mesh_state, b.structure.physics.mesh_state
    for name in ("force", "stiffness", "active", "delta", "load", "inside", "xi", "z"):
        np.testing.assert_array_equal(getattr(ma, name), getattr(mb, name), err_msg=name)
    assert (ma.total_load, ma.transmission_error, ma.contact_length) == (
        mb.total_load, mb.transmission_error, mb.contact_length)


def _same_rows(blocks, steps):
    assert len(blocks) == len(steps)
    for k, (b, s) in enumerate(zip(blocks, steps, strict=True)):
        for name, x, y in zip(("states", "force", "mesh force", "TE", "gear nodes",
                               "iterations"), b, s, strict=True):
            np.testing.assert_array_equal(x, y, err_msg=f"step {k + 1}: {name}")


def _compare(case, n, structure=None, threads=1, change=None, warm=0):
    """Steps 0 .. n - 1 of two masters, ``warm`` steps one by one, then ``change(master)``,
    then blocks against single steps: the same rows, errors and counters, and the same state
    after every block. Returns the masters, the error, the steps blocks took and the blocks
    of more than one step."""
    blocked, single = _masters(case, structure, threads)
    dt = time_step(case)
    for m in (blocked, single):
        assert _rows_of_steps(m, dt, 0, warm)[1] is None
        if change is not None:
            change(m)
    s_rows, done = [], [warm]

    def follow(i):  # the single steps up to step i, and the same state after them
        s_rows.extend(_rows_of_steps(single, dt, done[0], i)[0])
        done[0] = i
        _same_state(blocked, single)
        _same_mesh_state(blocked, single)
        assert _counters(blocked) == _counters(single)

    b_rows, b_error, in_blocks, long_blocks = _rows_of_blocks(blocked, dt, warm, n, follow)
    more, s_error = _rows_of_steps(single, dt, done[0], n)
    _same_rows(b_rows, s_rows + more)
    assert (type(b_error), str(b_error)) == (type(s_error), str(s_error))
    assert _counters(blocked)[:4] == _counters(single)[:4]
    return blocked, single, b_error, in_blocks, long_blocks


@pytest.mark.parametrize("name, model, steps", [("baguet2010_spur", "hybrid", 96),
                                                ("baguet2010_helical", "hybrid", 32),
                                                ("baguet2010_spur", "linear", 96),
                                                ("baguet2010_spur", "lumped", 96),
                                                ("baguet2010_spur", "short", 96)])
def test_blocks_give_the_bits_of_single_steps(name, model, steps):
    """Steps cut at contact events among them (test_fused counts them)."""
    blocked, single, error, in_blocks, long_blocks = _compare(
        load_case(name, {"bearings.*.model": model}), steps)
    assert error is None
    _same_state(blocked, single)
    assert _counters(blocked) == _counters(single)
    assert in_blocks == steps and long_blocks == -(-steps // BLOCK)


def test_blocks_with_gear_runouts_give_the_bits_of_single_steps():
    blocked, single, error, in_blocks, _ = _compare(load_case("baguet2010_spur"), 48,
                                                    structure=with_runout)
    assert error is None and in_blocks == 48
    _same_state(blocked, single)


def test_a_step_of_more_sub_steps_than_a_block_takes_ends_the_block(monkeypatch):
    """With room for one piece only, the helical case's cut steps (most of them) end their
    block and go through :meth:`Master.step` (the Python loop), with the same bits."""
    import gear_fmu.structure

    monkeypatch.setattr(gear_fmu.structure, "MAX_PIECES", 1)
    blocked, single, error, in_blocks, _ = _compare(load_case("baguet2010_helical"), 24)
    assert error is None and 0 < in_blocks < 12
    _same_state(blocked, single)


def test_blocks_through_the_relaxed_step_at_300_rad_s_give_the_same_bits():
    """Step 408 at 300 rad/s is relaxed (test_master)."""
    case = load_case("baguet2010_spur").with_overrides({"drive.speed": 300.0})
    blocked, single, error, _, _ = _compare(case, 13 * 32)
    assert error is None and blocked.relaxed_steps >= 1
    _same_state(blocked, single)


def test_a_step_that_does_not_converge_in_a_block_fails_alike():
    """Two coupled iterations allowed: step 39, the first that needs three, fails inside a
    block with the message of a single step, after the steps before it."""
    def two(m):
        m.max_iterations = 2

    blocked, single, error, in_blocks, _ = _compare(load_case("baguet2010_spur"), 96,
                                                    change=two)
    assert isinstance(error, CouplingError) and "did not converge in 2 iterations" in str(error)
    assert in_blocks == 38 and 38 % BLOCK != 0  # inside a block
    _same_state(blocked, single)


def test_a_failing_structure_step_in_a_block_fails_alike():
    """After 10 steps the structure is allowed no Newton pass: step 11, the first of a block,
    fails with the structure's own error (a failure inside a block: the test above)."""
    def no_pass(m):
        m.structure.physics.max_iter = 0

    blocked, single, error, in_blocks, _ = _compare(load_case("baguet2010_spur"), 96,
                                                    change=no_pass, warm=10)
    assert isinstance(error, NewmarkConvergenceError)
    assert str(error).startswith("Newmark step 11 at t = ") and "did not converge" in str(error)
    assert in_blocks == 0
    assert _counters(blocked) == _counters(single)


def test_a_failing_bearing_at_a_block_s_first_step_fails_alike():
    """Laws that throw the second shaft's journals out of their clearance (test_fused)."""
    def push(m):
        f0 = m.laws.f0.copy()
        f0[2:] += 1e7
        m.laws = AffineLaws(f0, m.laws.kb, m.laws.cb)

    _, _, error, _, _ = _compare(load_case("baguet2010_spur"), 8, change=push)
    assert isinstance(error, BearingError) and error.bearing_index == 2


def test_condensation_slots_that_fill_up_end_the_block_and_start_again(monkeypatch):
    """Room for 3 sub-step lengths (the helical case's cut steps have 2 or 3 pieces of
    recurring lengths): a step whose lengths do not fit ends its block, the next block starts
    with empty slots; the same bits."""
    from gear_fmu.step.condensation import CondensationSlots

    clears = []
    clear = CondensationSlots.clear
    monkeypatch.setattr(CondensationSlots, "CAPACITY", 3)
    monkeypatch.setattr(CondensationSlots, "clear", lambda self: clears.append(1) or clear(self))
    _, _, error, in_blocks, _ = _compare(load_case("baguet2010_helical"), 32)
    assert error is None and in_blocks == 32
    assert len(clears) >= 2


def _python_loop(m):
    """The master without its compiled step, as for slaves the compiled loop does not take
    (the FD model, FMUs): its blocks are :meth:`Master.step` in a loop."""
    m.fused = None


def test_blocks_of_the_python_loop_give_the_bits_of_single_steps_and_fail_alike():
    """Short bearings through the Python loop: the same rows, counters and state as single
    steps; a structure that fails from step 12 on (no Newton pass allowed) fails inside the
    second block, after the eleven steps before it, with the error of a single step."""
    case = load_case("baguet2010_spur", {"bearings.*.model": "short"})
    blocked, single, error, in_blocks, long_blocks = _compare(case, 24, change=_python_loop)
    assert blocked.fused is None and error is None
    assert in_blocks == 24 and long_blocks == -(-24 // BLOCK)
    _same_state(blocked, single)
    assert _counters(blocked) == _counters(single)

    def fail_from_step_12(m):
        _python_loop(m)
        do_step = m.structure.do_step

        def step(t, dt):
            if t > 10.5 * dt:
                m.structure.physics.max_iter = 0
            return do_step(t, dt)
        m.structure.do_step = step

    blocked, single, error, in_blocks, _ = _compare(case, 24, change=fail_from_step_12)
    assert isinstance(error, NewmarkConvergenceError)
    assert str(error).startswith("Newmark step 12 at t = ") and "did not converge" in str(error)
    assert in_blocks == 11 and 11 % BLOCK != 0  # inside a block
    assert _counters(blocked) == _counters(single)
