"""Every operating point of a wide random sweep runs to its end (issue 45): the hybrid solver
and the coupled step do not give up anywhere over speed 100-1500 rad/s, unbalance 0.3-3 mm,
helix angle 0-15 deg and torque 50-600 N m. Paper-scale runs: ``-m slow``."""

import numpy as np
import pytest

from fmu_src.examples import helix_overrides
from tests.helpers import run_paper_case

#: the points: speed [rad/s], unbalance e_mu [mm], helix angle [deg], torque [N m]
POINTS = [tuple(p) for p in np.random.default_rng(7).uniform(
    (100.0, 0.3, 0.0, 50.0), (1500.0, 3.0, 15.0, 600.0), size=(24, 4))]


@pytest.mark.slow
@pytest.mark.parametrize("speed, unbalance, helix, torque", POINTS,
                         ids=[f"{w:.0f}rad_s-{e:.2f}mm-{b:.1f}deg-{t:.0f}Nm"
                              for w, e, b, t in POINTS])
def test_a_random_operating_point_runs_the_paper_length(tmp_path, speed, unbalance, helix,
                                                        torque):
    """2048 mesh periods of the shipped spur case, made helical at that helix angle as the
    paper's sweep does (:func:`fmu_src.examples.helix_overrides`: the transverse module kept
    at 4 mm; spur below 0.5 deg), hybrid bearings, in-process: every step is taken (some
    perhaps in sub-steps, which the summary counts). Measured with these 24 points: all run,
    one of them with one step in sub-steps (9 s each on one core)."""
    overrides = {"drive.speed": speed, "gears.*.unbalance": f"{unbalance} mm",
                 "drive.torque": f"{torque} N.m"}
    if helix >= 0.5:
        overrides |= helix_overrides(helix)
    _, summary = run_paper_case(tmp_path, periods=2048, **overrides)
    assert summary.steps == 2048 * 32
