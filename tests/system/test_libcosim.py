"""libcosim (OSP's C++ co-simulation library, through libcosimpy) runs the transmission FMU.

libcosim keeps time in whole nanoseconds (the paper's step of 23,236.632 ns is 23,236 ns) and
does not iterate; the FMU iterates inside ``doStep``. libcosim passes the FMU
``currentCommunicationPoint = t_k`` and ``communicationStepSize = t_(k+1) - t_k`` with
``t_k = (k * step_ns) / 1e9`` in doubles (cosim/time.hpp: ``to_double_time_point``,
``to_double_duration``), so its steps differ from ``step_ns * 1e-9`` in their last bits:
:func:`libcosim_steps`. The FMU adds each step to its own time, which therefore stays
libcosim's ``t_k`` bit for bit at one internal step per communication step, so its check of
``currentCommunicationPoint`` (within 1e-9 relative) holds exactly; a cut step's n additions
of h / n drift from it slowly (in double arithmetic: 3.5e-11 relative after 10^6 steps of
100,000 ns). The reference is the master of ``gsb run`` stepping at those steps
(:func:`tests.system.test_transmission_fmu.master_rows`), computed here, independently of
libcosim and of the FMU's doStep.

Skipped where libcosimpy is not installed (``pip install libcosimpy``; 0.0.6 has wheels for
CPython 3.11 to 3.14 on Linux x86_64 and Windows, no sdist).
"""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from tests.helpers import run_isolated
from tests.system.test_transmission_fmu import (
    _case,
    _dt,
    _relative,
    _stepped_run_up,
    assert_same_run,
    master_rows,
)

if importlib.util.find_spec("libcosimpy") is None:
    pytest.skip("libcosimpy is not installed (pip install libcosimpy; wheels for CPython "
                "3.11 to 3.14 on Linux x86_64 and Windows)", allow_module_level=True)

STEP_NS = 23236  # the paper's 23,236.632 ns step, whole nanoseconds
STEPS = 32  # one mesh period


def libcosim_steps(step_ns: int, steps: int) -> list[float]:
    """The communication steps [s] libcosim passes to ``fmi2DoStep`` at a fixed step of
    ``step_ns`` nanoseconds: ``t_(k+1) - t_k``, each ``t_k`` the int64 nanosecond count over
    1e9 as a double (``std::chrono::duration_cast`` to ``duration<double>``)."""
    return [((k + 1) * step_ns) / 1e9 - (k * step_ns) / 1e9 for k in range(steps)]


def _simulate(fmu, step_ns: int, steps: int) -> dict:
    """The probe in a fresh interpreter (its exit code checked: 0)."""
    return run_isolated(module="tests.probes.libcosim",
                        args=["simulate", {"fmu": str(fmu), "step_ns": step_ns,
                                           "steps": steps}])


@pytest.fixture(scope="module")
def paper_step(transmission_fmu):
    """libcosim at 23,236 ns, STEPS steps."""
    return _simulate(transmission_fmu, STEP_NS, STEPS)


def test_libcosim_starts_at_x0_on_its_nanosecond_clock(paper_step):
    """The time-series observer's sample at the initialisation is the static solution X0 of
    ``gsb run``'s master (``SAME_RUN``: bit for bit, across the two processes);
    libcosim's clock reads k * 23,236 ns after step k."""
    got = paper_step
    x0 = master_rows(_case(), [], 0)[0]
    assert_same_run([got["series"][0]], [x0], "libcosim's X0")
    assert got["series_steps"] == list(range(STEPS + 1))
    assert got["series_times"] == [k * STEP_NS for k in range(STEPS + 1)]
    assert got["times"] == [k * STEP_NS for k in range(1, STEPS + 1)]


def test_each_step_is_gsb_runs_master_at_libcosims_steps(paper_step):
    """After each step, the last-value observer's 26 outputs are those of ``gsb run``'s master
    stepping at libcosim's steps (:func:`libcosim_steps`; ``SAME_RUN``: bit for bit), one
    internal step each; the time-series observer recorded
    the same. Against the master at the constant step 23236e-9 s the outputs differ by 4.1e-10
    relative to each output's largest magnitude (newest versions; 1.4e-9 with the oldest
    allowed; measured over these 32 steps, on a velocity; asserted below 1e-8): a step's last
    bit grows along the trajectory (at 23,237 ns to 2.6e-8), far inside the master's
    tolerance (1e-5)."""
    got = paper_step
    case = _case()
    rows = np.array(got["rows"])
    exact = master_rows(case, libcosim_steps(STEP_NS, STEPS), STEPS)[1:]
    assert_same_run(rows, exact, f"libcosim at {STEP_NS} ns")
    assert np.array_equal(np.array(got["series"][1:]), rows)
    assert got["internal_steps"] == STEPS
    constant = _relative(rows, master_rows(case, 23236e-9, STEPS)[1:])
    print(f"\nlibcosim at {STEP_NS} ns vs gsb run's master at the constant step 23236e-9 s: "
          f"{constant:.1e} relative")
    assert 0 < constant < 1e-8


def test_a_longer_step_is_cut_into_internal_steps(transmission_fmu):
    """A 100,000 ns step (4.3 case steps) is 5 internal steps of a fifth of libcosim's step:
    ``gsb run``'s master at those steps, bit for bit, every fifth row."""
    from orchestrator.coupling.transmission import internal_steps

    step_ns, steps = 100_000, 8
    n = internal_steps(step_ns * 1e-9, _dt(_case()))
    assert n == 5
    got = _simulate(transmission_fmu, step_ns, steps)
    fine = [h / n for h in libcosim_steps(step_ns, steps) for _ in range(n)]
    ref = master_rows(_case(), fine, steps * n)[n::n]
    assert_same_run(got["rows"], ref, "libcosim, 5 internal steps a step")
    assert got["internal_steps"] == steps * n


def test_a_step_no_bearing_can_carry(transmission_fmu):
    """A torque of 2e5 N m set by libcosim's override manipulator after the first step: the
    step the FMU refuses (fmi2Discard) stops libcosim's execution (its state ERROR, no further
    step); the last-value observer's read after it (fmi2Error) puts the FMU's reason into
    libcosim's last error message (without an observer that message reads "Step not
    complete", the reason in libcosim's log only). The process exits with 0."""
    got = run_isolated(module="tests.probes.libcosim",
                       args=["impossible_step", {"fmu": str(transmission_fmu),
                                                 "step_ns": STEP_NS, "torque": 2e5,
                                                 "observe": True}])
    assert 1 < got["ok_steps"] < 50
    assert got["state"] == "ERROR" and got["step again"] is False
    assert "doStep from t = " in got["error"] and "failed: " in got["error"], got["error"]


def test_libcosim_drives_a_run_up_through_the_speed_input(transmission_fmu):
    """libcosim's override manipulator sets the input ``speed`` before each step to the speed
    a run-up reaches at its end (:func:`tests.system.test_transmission_fmu._stepped_run_up`;
    ``max_speed`` 400 rad/s an initial value, the step 18,880 ns): after each step the
    outputs are those of ``gsb run``'s master stepping at libcosim's steps, each step's speed
    followed as the FMU's do (:func:`~tests.system.test_transmission_fmu.master_rows`), bit
    for bit."""
    _, dt, speeds = _stepped_run_up(300)
    step_ns = round(dt * 1e9)
    got = run_isolated(module="tests.probes.libcosim", args=[
        "driven", {"fmu": str(transmission_fmu), "step_ns": step_ns, "speeds": speeds,
                   "max_speed": 400.0}])
    assert got["internal_steps"] == len(speeds)
    rows = master_rows(_case(), libcosim_steps(step_ns, len(speeds)), len(speeds), speeds)
    assert_same_run(got["rows"], rows[1:], f"libcosim driving the speed at {step_ns} ns")
    assert max(speeds) == 400.0
