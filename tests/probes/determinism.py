"""Probes of tests/system/test_determinism.py, each run in a fresh interpreter with a numba
cache of the test's choice. They import the packages inside the probe, after any change of
``sys.path``: the code a probe runs is the one it asks for."""

from __future__ import annotations

import hashlib
import sys
import tempfile

from tests.probes import dispatch, probes_of


def runs(fmu_dir: str | None, periods: int,
         transports: tuple[str, ...] = ("in-process", "fmu")) -> dict:
    """The paper's spur case in-process and through the FMUs (``transports``; the FMUs from
    ``fmu_dir``): per transport, a hash of the static solution and of every channel of the
    results file, and the number of rows."""
    import numpy as np

    from tests.helpers import run_paper_case

    out = {}
    for transport in transports:
        with tempfile.TemporaryDirectory() as tmp:
            r, s = run_paper_case(tmp, periods=periods, in_process=transport == "in-process",
                                  fmu_dir=fmu_dir)
        h = hashlib.sha256(np.ascontiguousarray(s.static_positions).tobytes())
        for name in sorted(r):
            if name not in ("units", "attrs", "coords"):
                h.update(name.encode() + np.ascontiguousarray(r[name]).tobytes())
        out[transport] = h.hexdigest()
        out[transport + " rows"] = len(r["time"])
    return out


def short_bearing_force(code: str) -> dict:
    """The short-bearing force at one state, computed by the copy of the packages in the
    folder ``code`` (first on the path), and the module the model came from."""
    sys.path.insert(0, code)
    from bearing_fmu import BearingData
    from bearing_fmu.short_bearing import ShortBearing

    r = ShortBearing(BearingData(0.07, 0.05, 150e-6, 0.0288)).evaluate(
        60e-6, -60e-6, 0.0, 0.0, 325.0)
    return {"force": r.force.tolist(), "file": ShortBearing.__module__}


def linear_algebra() -> dict:
    """What the structure's dense linear algebra feeds, as hashes: the helical case's first 16
    steps in-process (static solution, damping, Newmark matrices, steps) and the damped modes
    of the spur case about X0 (``gsb modal``), and the BLAS thread count of this process."""
    import numpy as np
    from threadpoolctl import threadpool_info

    import orchestrator as gsb
    from fmu_src.case import load_case
    from orchestrator.analysis.campbell import linearise

    r = gsb.simulate(load_case("baguet2010_helical"), in_process=True, steps=16, progress=False)
    run = hashlib.sha256()
    for name in sorted(r.channels):
        run.update(name.encode() + np.ascontiguousarray(r.channels[name]).tobytes())
    d = linearise(load_case("baguet2010_spur")).damped
    modes = hashlib.sha256(np.ascontiguousarray(d.frequency_hz).tobytes()
                           + np.ascontiguousarray(d.damping_ratio).tobytes())
    return {"helical run": run.hexdigest(), "spur modes": modes.hexdigest(),
            "blas threads": max(i["num_threads"] for i in threadpool_info()
                                if i["user_api"] == "blas")}


PROBES = probes_of(runs, short_bearing_force, linear_algebra)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
