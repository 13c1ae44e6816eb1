"""fmi2FreeInstance frees the instance: instantiate/free cycles in one process leave nothing
behind.

A host that creates and frees instances of an FMU in one process (a sweep, a test suite, a
master restarting its slaves) must not grow with each. Each FMU runs cycles of
fmi2Instantiate, setup, initialisation, a read of outputs, fmi2Terminate and fmi2FreeInstance
through fmpy in a process of its own (:mod:`tests.probes.instance_memory`):

* the slave object is gone as soon as fmi2FreeInstance returns, with Python's garbage
  collector off (the library calls the slave's ``_fmi_release``, which breaks the reference
  cycles its variables' getters and setters make: patch 0008 and
  fmu_src/slaves/support.py);
* resident memory grows by less than :data:`BOUND` per cycle, Python's garbage collected
  before each end and every few cycles (what stays behind, not what waits for the
  collector). With pythonfmu 0.7.0's library and this package's slaves before the fix, 78 to
  83 KiB per cycle for every FMU (the slave script, run again at each instantiation, piled
  up references to its namespace; the library kept every class the script defined, some
  7 KiB per cycle alone), and every freed slave still alive. After: 0 to 0.06 KiB per cycle
  (200 cycles after 100 of warm-up; the gear-shaft FMU 100 after 100).

Without the periodic collections the growth is that of the host's own garbage, which Python
collects when its thresholds say: 10,000 cycles of BearingHybrid through fmpy grew a process
by 2.6 MiB in all, nothing after the first 2,000 cycles.

BearingHybrid runs by default; every FMU with ``-m slow`` (the finite-difference and gear-shaft
FMUs take tens of milliseconds, respectively some 0.3 s, per cycle).
"""

from __future__ import annotations

import pytest

from bearing_fmu import MODELS
from fmu_src.contract import bearing_fmu_name
from tests.helpers import run_isolated

PROBES = "tests.probes.instance_memory"
#: growth of resident memory per cycle [bytes]: 1 KiB, 10 MiB over 10,000 cycles; the largest
#: measured is 61 B, the margin a step or two of the allocator (some 100 KiB in a run)
BOUND = 1024
#: (warm-up cycles, measured cycles, cycles with the collector off) per FMU: the caches of
#: the first cycles settle in the warm-up (the gear-shaft FMU's, whose cycle solves its
#: static and modal problems in some 0.3 s, within 100 cycles)
SIZES = {**{bearing_fmu_name(m): (100, 200, 10) for m in MODELS}, "GearShaft": (100, 100, 3)}
FAST = "BearingHybrid"


@pytest.mark.parametrize("fmu", [pytest.param(name, marks=() if name == FAST
                                              else pytest.mark.slow) for name in SIZES])
def test_freed_instances_leave_nothing_behind(fmu_dir, fmu):
    warm_up, cycles, held = SIZES[fmu]
    out = run_isolated(module=PROBES, args=["cycles", {
        "fmu": fmu_dir / f"{fmu}.fmu", "warm_up": warm_up, "cycles": cycles, "held": held}])
    print(f"\n{fmu}: {out['growth_per_cycle'] / 1024:.2f} KiB per instantiate/free cycle, "
          f"{out['alive']} of {held} freed slaves still alive")
    assert out["alive"] == 0, f"{out['alive']} of {held} slaves outlived fmi2FreeInstance"
    assert out["growth_per_cycle"] < BOUND, (
        f"resident memory grew by {out['growth_per_cycle']:.0f} B per cycle over {cycles} "
        f"cycles of {fmu}, above the bound of {BOUND} B")


@pytest.mark.slow
def test_freed_transmission_instances_leave_nothing_behind(transmission_fmu):
    """The transmission FMU (the master, the structure and four bearings per instance; each
    cycle solves X0): the same bounds, over the bearing FMUs' 200 cycles after 100. Over 60
    cycles after 60, one step of the allocator decided the figure: 8, 8 and 96 KiB in all
    (137-1638 B per cycle) in three runs, since each instance's mesh keeps its 9 KiB cache
    (gear_fmu.mesh.element); over 200 after 100: 0, 0 and 4 KiB; over 600 after 60: 16 KiB."""
    out = run_isolated(module=PROBES, args=["cycles", {
        "fmu": transmission_fmu, "warm_up": 100, "cycles": 200, "held": 3}])
    print(f"\ntransmission: {out['growth_per_cycle'] / 1024:.2f} KiB per instantiate/free "
          f"cycle, {out['alive']} of 3 freed slaves still alive")
    assert out["alive"] == 0
    assert out["growth_per_cycle"] < BOUND
