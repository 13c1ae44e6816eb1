"""Probes of tests/fmu_src/test_bearing_fmus.py: bearing FMUs driven through
:class:`orchestrator.coupling.fmi.FmuBearings` (run in the test's process)."""

from __future__ import annotations

import contextlib

import numpy as np

from tests.probes import counted_calls, dispatch, probes_of


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


def native_law(fmu: str, model: str, without_compiled_law: bool = False) -> dict:
    """The master's calls on one bearing FMU along a sequence of journal states (a frame
    turned and mirrored), with a journal outside the clearance and one where the law overflows
    among them, against the in-process model; and how many of the calls reached the slave's
    Python (``BearingSlave.set_real`` and ``get_real`` counted): the patched library serves
    the others with the compiled law (fmu_src/native/patches/0011-native-bearing-law.patch).
    ``without_compiled_law``: as if the compiled law could not be loaded (its module made
    unimportable); ``log`` has the FMU's messages."""
    import sys

    from bearing_fmu import BearingData, model_class
    from bearing_fmu.frames import LocalFrame
    from fmu_src.slaves.bearing import BearingSlave
    from orchestrator.coupling.fmi import FmuBearings, FmuError
    from orchestrator.coupling.inprocess import ModelBearings

    c = 110e-6
    params = dict(D=0.09, L=0.065, C=c, mu=0.0288, frame_angle=0.3, rotation_sign=-1)

    def reference():  # the in-process model, cold
        bearing = BearingData(0.09, 0.065, c, 0.0288)
        return ModelBearings([model_class(model).from_parameters(bearing)],
                             [LocalFrame(0.3, -1)], [54.0])

    ref = reference()
    with counted_calls(BearingSlave, ("set_real", "get_real")) as calls:
        native = "bearing_fmu.hybrid._native"
        was = sys.modules.get(native)
        if without_compiled_law:
            sys.modules[native] = None  # import raises ImportError
        try:
            fmu = FmuBearings([fmu], [params], [54.0])
        finally:
            if without_compiled_law:
                sys.modules.pop(native)
                if was is not None:
                    sys.modules[native] = was
        out = {"same": [], "errors": {}}
        calls.update(set_real=0, get_real=0)  # the evaluations' calls only
        try:
            states = [[0.4 * c, -0.3 * c, 1e-3, 0.0]]
            states += [[(0.4 + 0.02 * k) * c, -0.3 * c, 1e-3, -2e-3 * k] for k in range(1, 6)]
            # the journal outside the clearance (the state check), and a squeeze velocity at
            # which the hybrid solver does not converge (it starts cold next time): 1e300 m/s,
            # where its sums overflow (it converges up to 1e100 and beyond, the force linear
            # in the velocity there)
            bad = {2: ("outside", [1.2 * c, 0.0, 0.0, 0.0])}
            if model == "hybrid":
                bad[4] = ("fast", [0.4 * c, -0.3 * c, 1e300, 0.0])
            for k, state in enumerate(states):
                if k in bad:
                    name, x = bad[k]
                    with contextlib.suppress(Exception):
                        ref.evaluate(np.array([x]))
                    try:
                        fmu.evaluate(np.array([x]))
                        out["errors"][name] = None
                    except FmuError as exc:
                        out["errors"][name] = exc.reason
                x = np.array([state])
                same = all(np.array_equal(a, b) for a, b in zip(ref.evaluate(x), fmu.evaluate(x),
                                                                 strict=True))
                out["same"].append(bool(same))
            out["calls"] = dict(calls)
            s = fmu.slaves[0]
            out["n_solves"] = int(s.fmu.getInteger([s.vr["n_solves"]])[0])
            try:  # a state that is not finite: refused by the set, in the slave's Python
                fmu.evaluate(np.array([[np.nan, 0.0, 0.0, 0.0]]))
                out["nan"] = None
            except FmuError as exc:
                out["nan"] = exc.reason
            # the last state again (the refused set applied its finite values, as the
            # per-variable path does): the in-process model's law
            x = np.array([states[-1]])
            out["same_after_nan"] = all(np.array_equal(a, b) for a, b in zip(
                ref.evaluate(x), fmu.evaluate(x), strict=True))
            # fmi2Reset: a new slave, whose buffer the library asks for again
            s.fmu.reset()
            s.fmu.setupExperiment(startTime=0.0)
            s.fmu.enterInitializationMode()
            s.set({k: v for k, v in params.items() if k in s.vr} | {"omega": 54.0})
            ref = reference()
            calls.update(set_real=0, get_real=0)
            out["after_reset"] = [bool(all(np.array_equal(a, b) for a, b in zip(
                ref.evaluate(x), fmu.evaluate(x), strict=True)))
                for x in (np.array([state]) for state in states[:3])]
            out["calls_after_reset"] = dict(calls)
            out["log"] = list(s.messages)
        finally:
            fmu.close()
    return out


PROBES = probes_of(error_and_state_round_trip, linear_freeze, many_instances, native_law)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
