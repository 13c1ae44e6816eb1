"""The coupled step in-process (:mod:`orchestrator.coupling.step`): its counters against what
the iteration did, its failures, and the hybrid bearings on two threads against one.

The master's step was once written twice, a Python loop and a compiled one, and this module
(then ``test_fused``) compared the two. The step is defined once now: what it computes is
checked against independent references elsewhere (the monolithic Newton in ``test_master``,
the golden run, the FMU transport in ``test_fmu_steps``, single steps against blocks in
``test_blocks``); here the counters are checked against the iterations each step reports, the
failures against their causes, and two threads against one thread.
"""

from __future__ import annotations

import numpy as np
import pytest

from bearing_fmu.affine import AffineLaws
from bearing_fmu.base import BearingError
from fmu_src.case import load_case
from fmu_src.description import time_step
from gear_fmu.step.newmark import NewmarkConvergenceError
from orchestrator.coupling.master import SUBSTEPS, CouplingError
from orchestrator.coupling.system import build_master
from tests.helpers import need_threads


def _master(case, threads=1):
    m = build_master(case, in_process=True, threads=threads)
    m.solve_static()
    m.exit_initialization()
    return m


def _counters(m):
    return (m.total_iterations, m.total_bearing_evaluations, m.relaxed_steps,
            m.bearings.evaluations, m.structure.physics.n_steps, m.structure.physics.t)


def _same_state(a, b):
    sa, sb = a.structure.physics, b.structure.physics
    for name in ("x", "v", "a"):
        np.testing.assert_array_equal(getattr(sa, name), getattr(sb, name), err_msg=name)
    for x, y in zip(a.structure.step_outputs(), b.structure.step_outputs(), strict=True):
        np.testing.assert_array_equal(x, y)
    for name in ("f0", "kb", "cb", "states", "force_at"):
        np.testing.assert_array_equal(getattr(a.laws, name), getattr(b.laws, name), name)


def _delta(m, before):
    return tuple(x - y for x, y in zip(_counters(m)[:4], before[:4], strict=True))


def test_the_counters_are_what_the_iteration_did():
    """Accepted steps add their reported iterations (one structure solve and one evaluation
    of the bearing set each, every bearing once); a step that does not converge in 4 adds 4 of
    each; a structure that fails at its first solve adds none; a bearing set that fails at the
    first evaluation adds the evaluation of the set but no iteration and no bearing's
    evaluation (it is not accepted). The step that does not converge is taken again from its
    start in 2, 4 and 8 sub-steps (SUBSTEPS), whose first fails alike: 4 more each."""
    case = load_case("baguet2010_spur", {"bearings.*.model": "short"})
    m = _master(case)
    nb, dt = m.bearings.count, time_step(case)
    try:
        before = _counters(m)
        block = m.steps(0, dt, 16)
        assert block.error is None and block.count == 16
        it = int(block.iterations.sum())
        assert it > 16  # some steps iterate
        assert _delta(m, before) == (it, it, 0, nb * it)
        # no convergence: four iterations, each a solve and an evaluation
        state, laws = m.structure.get_state(), m.laws
        m.tol, m.max_iterations = 0.0, 4
        before = _counters(m)
        block = m.steps(16, dt, 3)
        assert isinstance(block.error, CouplingError) and block.count == 0
        tries = 1 + len(SUBSTEPS)
        assert _delta(m, before) == (4 * tries, 4 * tries, 0, 4 * nb * tries)
        assert "did not converge in 4 iterations" in str(block.error)
        assert "; nor in 2, 4, 8 sub-steps (" in str(block.error)
        # the structure fails at its first solve (no Newton pass allowed)
        m.structure.set_state(state)
        m.laws, m.tol, m.max_iterations = laws, case["simulation.tolerance"], 30
        max_iter, m.structure.physics.max_iter = m.structure.physics.max_iter, 0
        before = _counters(m)
        block = m.steps(16, dt, 3)
        assert isinstance(block.error, NewmarkConvergenceError) and block.count == 0
        assert str(block.error).startswith("Newmark step 17 at t = ")
        assert _delta(m, before) == (0, 0, 0, 0)
        # a bearing fails at the first evaluation
        m.structure.set_state(state)
        m.structure.physics.max_iter = max_iter
        f0 = laws.f0.copy()
        f0[2:] += 1e7
        m.laws = AffineLaws(f0, laws.kb, laws.cb)
        before = _counters(m)
        block = m.steps(16, dt, 3)
        assert isinstance(block.error, BearingError) and block.count == 0
        assert _delta(m, before) == (0, 1, 0, 0)
    finally:
        m.close()


def _push_second_shaft(m):
    """Laws that throw the journals of the second shaft out of their clearance."""
    laws = m.laws
    f0 = laws.f0.copy()
    f0[2:] += 1e7
    m.laws = AffineLaws(f0, laws.kb, laws.cb)


#: the master's coupled step with its bearings on threads is another compiled function (33 s
#: from an empty cache on 2 cores, a ninth of the default suite): slow; the threaded set's
#: bits and first failure are checked in the default run (tests/bearing_fmu/test_hybrid.py)
ON_THREADS = pytest.mark.slow


@pytest.mark.parametrize("model, threads", [("hybrid", 1),
                                            pytest.param("hybrid", 2, marks=ON_THREADS),
                                            ("short", 1)])
def test_a_failing_bearing_names_the_first_bearing_out_of_its_clearance(model, threads):
    """Bearings 3 and 4 pushed out: bearing 3 is reported (the first, also when two threads
    evaluate every bearing), by name and index, at its journal state, with its model's
    reason."""
    need_threads(threads)
    case = load_case("baguet2010_spur", {"bearings.*.model": model})
    m = _master(case, threads)
    try:
        dt = time_step(case)
        assert m.steps(0, dt, 2).error is None
        _push_second_shaft(m)
        block = m.steps(2, dt, 4)
        e = block.error
        assert isinstance(e, BearingError) and block.count == 0
        assert (e.bearing, e.bearing_index) == ("3", 2)
        assert e.state.shape == (4,)
        assert np.hypot(*e.state[:2]) >= case["bearings.3.clearance"]
        assert "eccentricity" in str(e)
    finally:
        m.close()


def test_bearings_of_two_models_name_the_failing_bearing_of_lowest_index():
    """Bearings 1, 2 and 4 hybrid, 3 short: the hybrid group is evaluated first and fails at
    bearing 4, the short one at bearing 3; bearing 3 is reported (the lowest index, whatever
    the order of the groups)."""
    case = load_case("baguet2010_spur", {"bearings.*.model": "hybrid",
                                         "bearings.3.model": "short"})
    m = _master(case)
    try:
        dt = time_step(case)
        assert m.steps(0, dt, 2).error is None
        _push_second_shaft(m)
        e = m.steps(2, dt, 4).error
        assert isinstance(e, BearingError)
        assert (e.bearing, e.bearing_index) == ("3", 2)
        assert "eccentricity" in str(e)
    finally:
        m.close()


def test_one_compiled_step_whatever_the_mix_of_bearing_models():
    """The bearing slots of :func:`coupled_steps` have one numba type for every model and mix
    of models in-process, whatever the hybrid grid (a group on threads and hybrid bearings of
    two grids aside): the step is compiled once, not once per mix (it once was, 17 times in a
    run of the tests)."""
    import numba

    from bearing_fmu import MODELS
    from orchestrator.coupling.step import bearing_slots

    mixes = [{"bearings.*.model": model} for model in MODELS] + [
        {"bearings.*.model": "hybrid", "bearings.2.model": "short", "bearings.3.model": "fd",
         "bearings.4.model": "linear"},
        {"bearings.*.model": "lumped", "bearings.1.model": "hybrid",
         "bearings.2.model": "hybrid", "bearings.1.nodes": 32, "bearings.2.nodes": 32}]
    types = set()
    for overrides in mixes:
        m = build_master(load_case("baguet2010_spur", overrides), in_process=True)
        try:
            types.add(numba.typeof(bearing_slots(m.bearings.compiled_groups())))
        finally:
            m.close()
    one_each = numba.typeof(bearing_slots(()))
    assert types == {one_each}, [str(t)[:300] for t in types]


@ON_THREADS
@pytest.mark.parametrize("name, steps", [("baguet2010_spur", 32), ("baguet2010_helical", 16)])
def test_bearings_on_two_threads_give_the_bits_of_one(name, steps):
    """The hybrid bearings shared by two threads (``build_master(threads=2)``) against one
    thread: the same bits step for step and in blocks (each bearing is the serial call on its
    own memory)."""
    need_threads(2)
    case = load_case(name)
    one, two = _master(case, 1), _master(case, 2)
    try:
        assert [s.threads for s in two.bearings.hybrid_sets] == [2]
        dt = time_step(case)
        half = steps // 2
        for i in range(half):
            ra, rb = one.step(i * dt, dt), two.step(i * dt, dt)
            assert (ra.iterations, ra.mismatch) == (rb.iterations, rb.mismatch), f"step {i + 1}"
            np.testing.assert_array_equal(ra.states, rb.states)
        done = half
        while done < steps:
            a = one.steps(done, dt, steps - done)
            b = two.steps(done, dt, a.count)
            assert a.error is None and b.error is None and a.count == b.count
            for field in ("states", "bearing_force", "mesh_force", "iterations"):
                np.testing.assert_array_equal(getattr(a, field), getattr(b, field), field)
            done += a.count
        _same_state(one, two)
        assert _counters(one) == _counters(two)
    finally:
        one.close()
        two.close()


def test_threads_for_bearings_that_are_not_hybrid_ones_are_said_to_do_nothing():
    """The linear bearings (an affine law each) are not shared: said once, one thread; a
    count out of range is refused as for hybrid bearings."""
    need_threads(2)
    with pytest.warns(RuntimeWarning, match=r"threads = 2: bearings other than hybrid run on "
                                            r"one thread \(threads share hybrid bearings "
                                            r"only\)"):
        m = build_master(load_case("baguet2010_spur", {"bearings.*.model": "linear"}),
                         in_process=True, threads=2)
    assert m.bearings.hybrid_sets == []
    with pytest.raises(ValueError, match=r"threads = 0: need a whole number from 1 to"):
        build_master(load_case("baguet2010_spur", {"bearings.*.model": "linear"}),
                     in_process=True, threads=0)  # the count is checked all the same
