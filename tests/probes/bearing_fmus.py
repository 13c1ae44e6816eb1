"""Probes of tests/fmu_src/test_bearing_fmus.py: bearing FMUs driven through
:class:`orchestrator.coupling.fmi.FmuBearings` (run in the test's process)."""

from __future__ import annotations

import numpy as np

from tests.probes import dispatch, probes_of


def error_and_state_round_trip(fmu: str) -> dict:
    """An evaluation outside the clearance is an FmuError; a state saved before it restores
    the same force."""
    from orchestrator.coupling.fmi import FmuBearings, FmuError

    bearings = FmuBearings([fmu], [dict()], [325.0])
    good = np.array([[6e-5, -6e-5, 0.0, 0.0]])
    f_good = bearings.evaluate(good)[0]
    s = bearings.slaves[0].fmu
    st = s.getFMUstate()
    try:
        bearings.evaluate(np.array([[2e-4, 0.0, 0.0, 0.0]]))  # eccentricity 1.33
        msg = None
    except FmuError as exc:
        msg = str(exc)
    s.setFMUstate(st)
    f_back = bearings.evaluate(good)[0]
    bearings.close()
    return dict(msg=msg, same=bool(np.array_equal(f_good, f_back)))


def linear_freeze(fmu: str) -> dict:
    """The linear bearing FMU before and after initialisation ends: how far from affine, from
    its film at X0, and whether its stiffness stays fixed."""
    from orchestrator.coupling.fmi import FmuBearings

    bearings = FmuBearings([fmu], [dict()], [325.0])
    x0 = np.array([[6e-5, -6e-5, 0.0, 0.0]])
    f0, k0, _ = bearings.evaluate(x0)
    bearings.exit_initialization()
    fa, ka, ca = bearings.evaluate(x0)
    x1 = x0 + np.array([[5e-6, 2e-6, 1e-4, -1e-4]])
    f1, k1, _ = bearings.evaluate(x1)
    pred = fa[0] - ka[0] @ (x1[0, :2] - x0[0, :2]) - ca[0] @ x1[0, 2:]
    bearings.close()
    scale = np.abs(f0).max()
    return dict(affine=float(np.abs(f1[0] - pred).max() / scale),
                at_x0=float(np.abs(fa - f0).max() / scale),
                k=float(np.abs(ka - k0).max() / np.abs(k0).max()),
                same_k=bool(np.array_equal(ka, k1)))


def many_instances(fmu: str) -> dict:
    """Five bearing sets of four instances of one FMU: the same force from each."""
    from orchestrator.coupling.fmi import FmuBearings

    sets = [FmuBearings([fmu] * 4, [dict()] * 4, [325.0] * 4) for _ in range(5)]
    st = np.tile([6e-5, -6e-5, 0.0, 0.0], (4, 1))
    f = [s.evaluate(st)[0] for s in sets]
    for s in sets:
        s.close()
    return dict(same=bool(all(np.array_equal(f[0], g) for g in f)))


PROBES = probes_of(error_and_state_round_trip, linear_freeze, many_instances)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
