"""Probes of tests/system/test_determinism.py, each run in a fresh interpreter with a numba
cache of the test's choice. They import the packages inside the probe, after any change of
``sys.path``: the code a probe runs is the one it asks for."""

from __future__ import annotations

import hashlib
import sys
import tempfile

from tests.probes import dispatch, probes_of


def runs(fmu_dir: str, periods: int) -> dict:
    """The paper's spur case in-process and through the FMUs: per transport, a hash of the
    static solution and of every channel of the results file, and the number of rows."""
    import numpy as np

    from tests.helpers import run_paper_case

    out = {}
    for transport in ("in-process", "fmu"):
        with tempfile.TemporaryDirectory() as tmp:
            r, s = run_paper_case(tmp, periods=periods, in_process=transport == "in-process",
                                  fmu_dir=fmu_dir)
        h = hashlib.sha256(np.ascontiguousarray(s.static_positions).tobytes())
        for name in sorted(r):
            if name not in ("units", "attrs"):
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


PROBES = probes_of(runs, short_bearing_force)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
