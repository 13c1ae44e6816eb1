"""The master's compiled coupled iteration (orchestrator.fused) changes nothing but the time.

The paper's spur case with hybrid bearings, in process, stepped by the master with the fused
iteration and with it switched off (every iteration through the slaves' interfaces): the
journal states, bearing forces and mesh forces agree to the last bit, and the fused iteration
served most of the iterations (the others: steps cut at a contact event). The independent
check of the physics is the golden run (tests/test_golden.py), which these iterations
reproduce exactly.
"""

import numpy as np

from fmu_src.case import load_case
from orchestrator.fused import FusedIteration
from orchestrator.run import build_master

STEPS = 96  # three mesh periods


def run(fused: bool, served: list):
    case = load_case("baguet2010_spur")
    master = build_master(case, in_process=True)
    assert isinstance(master._fused, FusedIteration)
    inner = master._fused

    def counting(t, dt, laws):
        done = inner(t, dt, laws)
        served.append(done is not None)
        return done

    master._fused = counting if fused else None
    master.solve_static()
    master.exit_initialization()
    dt = master.structure.structure.mesh_period / case["simulation.steps_per_mesh_period"]
    rows = []
    for i in range(STEPS):
        r = master.step(i * dt, dt)
        rows.append(np.concatenate([r.states.ravel(), r.bearing_force.ravel(),
                                    [master.structure.mesh_force(), r.iterations]]))
    return np.array(rows)


def test_fused_iteration_gives_the_general_iteration_bit_for_bit():
    served = []
    fused = run(True, served)
    general = run(False, [])
    assert np.array_equal(fused, general)
    share = np.mean(served)
    print(f"\nfused iteration served {share:.0%} of {len(served)} iterations")
    assert share > 0.8  # measured 0.94: the steps with a contact event go the general way
