"""The master's step as one compiled call (:mod:`orchestrator.coupling.fused`) against the
Python loop it replaces (:meth:`Master.step` without ``fused``): the same bits, counters and
errors, step for step, spur and helical, hybrid, short, linear and lumped bearings, through
the relaxation and the steps cut at contact events; the FD model keeps the Python loop.
The physics of the step is asserted elsewhere (the monolithic Newton, the golden run, the
order); the compiled steps through FMUs have their own comparison (``test_fmu_steps``), and the
FMU suites compare the FMU runs with in-process runs bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from bearing_fmu.affine import AffineLaws
from bearing_fmu.base import BearingError
from fmu_src.case import load_case
from fmu_src.description import time_step
from gear_fmu.step.newmark import NewmarkConvergenceError
from orchestrator.coupling import fused as fused_module
from orchestrator.coupling.master import CouplingError
from orchestrator.coupling.system import build_master


def _pair(case, structure=None, threads=(1, 1)):
    """Two masters of ``case`` after the static solution: the compiled step and the Python
    loop (each on a structure from ``structure(case)`` if given, their hybrid bearings on
    ``threads`` threads)."""
    out = []
    for compiled, n in zip((True, False), threads, strict=True):
        m = build_master(case, in_process=True,
                         structure=None if structure is None else structure(case), threads=n)
        assert m.fused is not None
        if not compiled:
            m.fused = None
        m.solve_static()
        m.exit_initialization()
        out.append(m)
    return out


def _counters(m):
    return (m.total_iterations, m.total_bearing_evaluations, m.relaxed_steps,
            m.bearings.evaluations, m.structure.physics.n_steps, m.structure.physics.t)


def _same_state(a, b):
    sa, sb = a.structure.physics, b.structure.physics
    for name in ("x", "v", "a", "active"):
        np.testing.assert_array_equal(getattr(sa, name), getattr(sb, name), err_msg=name)
    assert sa.mesh_force() == sb.mesh_force()
    assert sa.transmission_error() == sb.transmission_error()
    for name in ("f0", "kb", "cb", "states", "force_at"):
        np.testing.assert_array_equal(getattr(a.laws, name), getattr(b.laws, name), name)


def _run_both(case, steps, monkeypatch, structure=None, threads=(1, 1)):
    compiled, python = _pair(case, structure, threads)
    taken = []
    step = fused_module.FusedStep.step
    monkeypatch.setattr(fused_module.FusedStep, "step",
                        lambda self, *a: taken.append(step(self, *a)) or taken[-1])
    dt = time_step(case)
    events = 0
    for i in range(steps):
        events += any(after is not None for *_, after in python.structure.physics._pieces(dt))
        rc, rp = compiled.step(i * dt, dt), python.step(i * dt, dt)
        assert (rc.iterations, rc.mismatch) == (rp.iterations, rp.mismatch), f"step {i + 1}"
        np.testing.assert_array_equal(rc.bearing_force, rp.bearing_force)
        np.testing.assert_array_equal(rc.states, rp.states)
    _same_state(compiled, python)
    assert _counters(compiled) == _counters(python)
    return compiled, sum(r is not None for r in taken), events


@pytest.mark.parametrize("name, model, steps", [("baguet2010_spur", "hybrid", 64),
                                                ("baguet2010_helical", "hybrid", 24),
                                                ("baguet2010_spur", "linear", 64),
                                                ("baguet2010_helical", "lumped", 24),
                                                ("baguet2010_spur", "short", 64)])
def test_the_compiled_step_gives_the_bits_of_the_python_loop(name, model, steps, monkeypatch):
    """Every step compiled, those cut at contact events (sub-steps and acceleration jumps)
    among them."""
    _, n_compiled, events = _run_both(load_case(name, {"bearings.*.model": model}), steps,
                                      monkeypatch)
    assert n_compiled == steps
    assert 0 < events < steps


def _with_runout(case):
    """The case's structure with gear runouts: error displacements of the gear nodes at every
    mesh evaluation, the ones after the contact events included."""
    from fmu_src import description
    from gear_fmu.mesh.element import MeshElement, ToothDeviations
    from gear_fmu.structure import Structure

    pair = description.gear_pair(case)
    mesh = MeshElement(pair, pair.nominal_line_load(case["drive.torque"]),
                       deviations=ToothDeviations(runout=(20e-6, 10e-6),
                                                  runout_phase=(0.3, 1.1)))
    assert mesh.has_errors
    return Structure(description.gear_shaft_system(case, pair), mesh,
                     description.structure_loads(case), zeta=description.damping(case),
                     tol=case["simulation.tolerance"],
                     consistent_start=case["simulation.consistent_start"],
                     locate_contact=case["simulation.locate_contact"])


def test_gear_runouts_give_the_same_bits(monkeypatch):
    _, n_compiled, events = _run_both(load_case("baguet2010_spur"), 40, monkeypatch,
                                      structure=_with_runout)
    assert n_compiled == 40 and events > 0


def test_a_step_with_more_sub_steps_than_the_compiled_loop_takes_goes_to_the_python_loop(
        monkeypatch):
    """With room for one piece only, the steps cut at their events take the Python loop
    (the helical case: 2 or 3 pieces in most steps), with the same bits."""
    import gear_fmu.structure

    monkeypatch.setattr(gear_fmu.structure, "MAX_PIECES", 1)
    _, n_compiled, events = _run_both(load_case("baguet2010_helical"), 24, monkeypatch)
    assert events > 0
    assert n_compiled == 24 - events


def test_the_relaxed_step_at_300_rad_s_gives_the_same_bits(monkeypatch):
    """Step 408 at 300 rad/s puts Newton into a two-cycle and is relaxed (test_master)."""
    case = load_case("baguet2010_spur").with_overrides({"drive.speed": 300.0})
    compiled, _, _ = _run_both(case, 13 * 32, monkeypatch)
    assert compiled.relaxed_steps >= 1


def _fail_both(case, change, monkeypatch, threads=(1, 1)):
    """The exception of one step of each master after ``change(master)``, and the counters;
    the compiled master's step must not have left it to the Python loop."""
    step = fused_module.FusedStep.step
    left = []

    def spy(self, *a):
        left.append(self)  # the compiled loop raises or returns a report, never None
        report = step(self, *a)
        left.pop()
        return report

    monkeypatch.setattr(fused_module.FusedStep, "step", spy)
    out = []
    for m in _pair(case, threads=threads):
        change(m)
        dt = time_step(case)
        with pytest.raises(Exception) as info:
            m.step(0.0, dt)
        # where a failed step leaves the structure is not compared: the Python loop leaves
        # it at the last iterate (or before it), the compiled one before the step, and a run
        # stops there without a checkpoint (orchestrator.run.runner)
        out.append((type(info.value), str(info.value), _counters(m)[:4],
                    getattr(info.value, "bearing", None)))
    assert len(left) == 1  # the compiled master's step raised inside the compiled path
    return out


def test_a_step_that_does_not_converge_fails_alike(monkeypatch):
    def never(m):
        m.tol, m.max_iterations = 0.0, 4

    compiled, python = _fail_both(load_case("baguet2010_spur"), never, monkeypatch)
    assert compiled == python
    assert compiled[0] is CouplingError and "did not converge in 4 iterations" in compiled[1]


def _push_second_shaft(m):
    """Laws that throw the journals of the second shaft out of their clearance."""
    laws = m.laws
    f0 = laws.f0.copy()
    f0[2:] += 1e7
    m.laws = AffineLaws(f0, laws.kb, laws.cb)


@pytest.mark.parametrize("threads", [(1, 1), (2, 1), (1, 2)], ids=["1", "2-compiled", "2-loop"])
def test_a_failing_bearing_fails_alike(threads, monkeypatch):
    _need_threads(max(threads))
    """Bearing 3's state check, also when the bearings share two threads (every bearing is
    evaluated there; the first failing one is reported, as the serial loop, which stops at
    it)."""
    compiled, python = _fail_both(load_case("baguet2010_spur"), _push_second_shaft,
                                  monkeypatch, threads)
    assert compiled == python
    assert issubclass(compiled[0], BearingError)
    assert compiled[3] == 3


def test_a_failing_short_bearing_fails_alike(monkeypatch):
    """The short bearings' set (:class:`bearing_fmu.short_bearing.ShortSet`) reports the state
    check of the first bearing out of its clearance, as the Python loop."""
    case = load_case("baguet2010_spur", {"bearings.*.model": "short"})
    compiled, python = _fail_both(case, _push_second_shaft, monkeypatch)
    assert compiled == python
    assert issubclass(compiled[0], BearingError) and "eccentricity ratio" in compiled[1]
    assert compiled[3] == 3


@pytest.mark.parametrize("name, steps", [("baguet2010_spur", 32), ("baguet2010_helical", 16)])
@pytest.mark.parametrize("threads", [(2, 1), (1, 2)], ids=["2-compiled", "2-loop"])
def test_bearings_on_two_threads_give_the_bits_of_one(name, steps, threads, monkeypatch):
    """The hybrid bearings shared by two threads (``build_master(threads=2)``), in the
    compiled step or in the Python loop, against one thread in the other path: the same bits
    step for step (each bearing is the serial call on its own memory)."""
    _need_threads(2)
    compiled, n_compiled, _ = _run_both(load_case(name), steps, monkeypatch, threads=threads)
    assert n_compiled == steps
    assert compiled.bearings.hybrid_set.threads == threads[0]


def test_blocks_on_two_threads_give_the_bits_of_single_steps_on_two():
    """Blocks of steps (``test_blocks``) with the bearings on two threads, here where the
    threaded kernel is compiled once for the suite's worker."""
    from tests.orchestrator.coupling.test_blocks import _compare

    _need_threads(2)
    blocked, single, error, in_blocks, _ = _compare(load_case("baguet2010_spur"), 48,
                                                    threads=2)
    assert error is None and in_blocks == 48
    _same_state(blocked, single)


def test_threads_for_bearings_that_are_not_hybrid_ones_are_said_to_do_nothing():
    """The linear bearings (an affine law each) are not shared: said once, one thread; a
    count out of range is refused as for hybrid bearings."""
    _need_threads(2)
    with pytest.warns(RuntimeWarning, match=r"threads = 2: the linear bearings run on one "
                                            r"thread \(threads share hybrid bearings only\)"):
        m = build_master(load_case("baguet2010_spur", {"bearings.*.model": "linear"}),
                         in_process=True, threads=2)
    assert m.bearings.hybrid_set is None
    with pytest.raises(ValueError, match=r"threads = 0: need a whole number from 1 to"):
        build_master(load_case("baguet2010_spur", {"bearings.*.model": "linear"}),
                     in_process=True, threads=0)  # the count is checked all the same


def _need_threads(n):
    """Skip unless numba can give the bearings ``n`` threads here."""
    import numba

    from bearing_fmu.hybrid.model import threading_layer

    if n > 1 and (numba.config.NUMBA_NUM_THREADS < n or threading_layer() is None):
        pytest.skip(f"numba cannot run {n} threads here (NUMBA_NUM_THREADS "
                    f"{numba.config.NUMBA_NUM_THREADS}, threading layer {threading_layer()})")


def test_a_failing_structure_step_fails_alike(monkeypatch):
    """A structure allowed no Newton pass: its own non-convergence error."""
    def no_pass(m):
        m.structure.physics.max_iter = 0

    compiled, python = _fail_both(load_case("baguet2010_spur"), no_pass, monkeypatch)
    assert compiled == python
    assert compiled[0] is NewmarkConvergenceError and "did not converge" in compiled[1]


def test_every_bearing_model_but_fd_takes_the_compiled_step():
    """Hybrid, short and affine bearings take the compiled step; the FD model the Python
    loop."""
    from bearing_fmu import MODELS

    for model in MODELS:
        m = build_master(load_case("baguet2010_spur", {"bearings.*.model": model}),
                         in_process=True)
        assert (m.fused is not None) == (model != "fd"), model
