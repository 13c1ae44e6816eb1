"""Blocks of coupled steps in one compiled call (:meth:`Master.steps`,
:func:`orchestrator.coupling.step.coupled_steps`) against the same steps one call each
(:meth:`Master.step`, a block of one): the same bits, counters and errors, step for step,
spur and helical, hybrid, short, linear and lumped bearings, with gear runouts, through the
relaxation, with condensation slots that fill up and end a block (on two threads:
``test_step``). A block carries the structure's plan, state and mesh evaluations from step to
step where single steps start each from the slave's state: this checks that hand-over. The
physics of the step is asserted elsewhere (the monolithic Newton, the golden run, the order);
the FMU transport against the in-process one in ``test_fmu_steps``. (The master's Python loop,
whose blocks this module also compared with single steps, no longer exists.)"""

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
from tests.orchestrator.coupling.test_step import _counters, _same_state

#: gear runouts (error displacements of the gear nodes at every mesh evaluation, the ones
#: after the contact events included)
RUNOUT = {"gears.pinion.runout": 20e-6, "gears.gear.runout": 10e-6,
          "gears.pinion.runout_phase": 0.3, "gears.gear.runout_phase": 1.1}

#: block length of these tests: short, so that blocks end at their length, at contact
#: events and at the end of the run
BLOCK = 7


def _masters(case, threads=1):
    """Two masters of ``case`` after the static solution."""
    out = []
    for _ in range(2):
        m = build_master(case, in_process=True, threads=threads)
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
    force, errors, nodes = st.step_outputs()
    return [(r.states.copy(), r.bearing_force.copy(), force, errors, nodes, r.iterations)], None


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
    """The structures' mesh evaluations, every array and figure of every mesh (the load along
    the face width of Fig. 13 included)."""
    states_a, states_b = a.structure.physics.mesh_states, b.structure.physics.mesh_states
    for ma, mb in zip(states_a, states_b, strict=True):
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


def _compare(case, n, threads=1, change=None, warm=0):
    """Steps 0 .. n - 1 of two masters, ``warm`` steps one by one, then ``change(master)``,
    then blocks against single steps: the same rows, errors and counters, and the same state
    after every block. Returns the masters, the error, the steps blocks took and the blocks
    of more than one step."""
    blocked, single = _masters(case, threads)
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
    """Steps cut at contact events among them."""
    blocked, single, error, in_blocks, long_blocks = _compare(
        load_case(name, {"bearings.*.model": model}), steps)
    assert error is None
    _same_state(blocked, single)
    assert _counters(blocked) == _counters(single)
    assert in_blocks == steps and long_blocks == -(-steps // BLOCK)


def test_blocks_with_gear_runouts_give_the_bits_of_single_steps():
    case = load_case("baguet2010_spur", RUNOUT)
    assert any(m.has_errors for m in build_master(case, in_process=True).structure.physics.meshes)
    blocked, single, error, in_blocks, _ = _compare(case, 48)
    assert error is None and in_blocks == 48
    _same_state(blocked, single)


def test_blocks_through_the_relaxed_step_at_300_rad_s_give_the_same_bits():
    """Step 408 at 300 rad/s is relaxed (test_master)."""
    case = load_case("baguet2010_spur").with_overrides({"drive.speed": 300.0})
    blocked, single, error, _, _ = _compare(case, 13 * 32)
    assert error is None and blocked.relaxed_steps >= 1
    _same_state(blocked, single)


def test_a_step_that_does_not_converge_in_a_block_fails_alike():
    """Two coupled iterations allowed: step 39, the first that needs three, is taken in 4
    sub-steps (SUBSTEPS), and step 40 fails even in 8, inside a block, with the message of a
    single step, after the steps before it."""
    def two(m):
        m.max_iterations = 2

    blocked, single, error, in_blocks, _ = _compare(load_case("baguet2010_spur"), 96,
                                                    change=two)
    assert isinstance(error, CouplingError) and "did not converge in 2 iterations" in str(error)
    assert "; nor in 2, 4, 8 sub-steps (" in str(error)
    assert in_blocks == 39 and 39 % BLOCK != 0  # inside a block
    dt = time_step(load_case("baguet2010_spur"))
    assert [(round(t / dt), m) for t, m in blocked.substepped] == [(38, 4)]
    assert blocked.substepped == single.substepped
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
    """Laws that throw the second shaft's journals out of their clearance (test_step)."""
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

