"""The Campbell diagram's data, one structure linearised at every speed
(:class:`orchestrator.analysis.campbell.Linearisation`), against each speed's case linearised on
its own the straightforward way: a master built for that case alone, its X0, its damping, its
mean mesh stiffness and its damped modes."""

import numpy as np
import pytest

from fmu_src.case import load_case
from gear_fmu.modal.analyses import exact_mean_mesh_stiffness
from gear_fmu.modal.damped_modes import damped_modes
from orchestrator.analysis.campbell import campbell_data
from orchestrator.coupling.system import build_master

SPUR = "baguet2010_spur"
KEYS = ("frequency_hz", "damping_ratio", "mesh_energy_fraction", "shapes")


def straightforward_modes(case, bearing_stiffness=None, n_gauss=8, max_frequency=6000.0):
    """The kept damped modes of one case about its X0, everything built for this case alone
    (as ``gsb run`` builds its master), in the diagram's selection: oscillating, below
    ``1.5 max_frequency``."""
    master = build_master(case, in_process=True)
    try:
        st = master.structure.structure
        if bearing_stiffness is None:
            master.solve_static()
            master.exit_initialization()
            kb = np.array(master.laws.kb, dtype=float)
            cb = np.array(master.laws.cb, dtype=float)
            kb_ref = 0.5 * (kb + np.transpose(kb, (0, 2, 1)))
        else:
            kb = np.broadcast_to(bearing_stiffness * np.eye(2), (4, 2, 2)).copy()
            cb = np.zeros((4, 2, 2))
            kb_ref = bearing_stiffness
            st.set_damping_reference(bearing_stiffness)
        k_mesh = exact_mean_mesh_stiffness(st, kb_ref, n_gauss)
        d = damped_modes(st.system, st.damping_full, k_mesh, kb, cb)
    finally:
        master.close()
    f = d.frequency_hz
    sel = (~d.overdamped) & (f <= 1.5 * max_frequency)
    return {"frequency_hz": f[sel], "damping_ratio": d.damping_ratio[sel],
            "mesh_energy_fraction": d.mesh_energy_fraction[sel], "shapes": d.shapes[:, sel]}


@pytest.mark.parametrize("bearing_stiffness", [None, 3e8], ids=["film", "isotropic"])
def test_campbell_modes_equal_each_speed_linearised_on_its_own(bearing_stiffness):
    """Every speed after the first is linearised on a structure that served other speeds
    before: its modes equal bit for bit (the same arithmetic) those of its case built alone.
    With the bearings' film the speeds differ (Kb, Cb and the damping C built on Kb change
    with the speed), so a bearing state, a damping or an X0 carried over from the previous
    speed would show; with isotropic bearings nothing depends on the speed."""
    case = load_case(SPUR)
    speeds = [1400.0, 150.0, 650.0]  # not monotonic: nothing may depend on the neighbour
    data = campbell_data(case, speeds, bearing_stiffness)
    assert data["speeds"].tolist() == speeds and not data["skipped"]
    for i in (1, 2):
        alone = straightforward_modes(case.with_overrides({"drive.speed": speeds[i]}),
                                      bearing_stiffness)
        got = data["modes"][i]
        assert got["frequency_hz"].size > 10
        for key in KEYS:
            assert np.array_equal(got[key], alone[key], equal_nan=True), (speeds[i], key)
    first, last = data["modes"][1]["frequency_hz"], data["modes"][2]["frequency_hz"]
    if bearing_stiffness is None:  # the film moved the modes between the speeds
        assert first.shape != last.shape or np.max(np.abs(first - last) / last) > 1e-3
    else:
        assert np.array_equal(first, last)
