"""µs per force + Jacobian call of the film bearing models, after numba warm-up.

    .venv/bin/python benchmarks/bearing_models.py

The states follow an orbit of radius 0.05 C around eccentricity 0.6 (L/D 0.714, the paper's
pinion bearing), with velocities, 1,024 calls per orbit as in a time-stepping run: each call is
warm-started from the previous one. Calls go through ``FilmBearingModel.dimensionless`` (state
validation included). The hybrid, short-bearing and finite-difference models are timed if they
are importable; ratios are against the hybrid n = 192 timed in the same process.
"""

import math
import platform
import time

import numpy as np

from bearing_fmu import BearingData
from bearing_fmu.hybrid.model import HybridBearing

try:
    from bearing_fmu.short_bearing import ShortBearing
except ImportError:
    ShortBearing = None
try:
    from bearing_fmu.fd.model import FiniteDifferenceBearing
except ImportError:
    FiniteDifferenceBearing = None


def orbit(n_calls):
    """(n_calls, 4) dimensionless states: 1,024 per orbit (the paper's run takes 65,536 steps for
    ~60 pinion revolutions, ~1,100 steps per unbalance orbit)."""
    ph = 2 * math.pi * np.arange(n_calls) / 1024.0
    return np.column_stack([0.6 + 0.05 * np.cos(ph), 0.05 * np.sin(ph),
                            -0.02 * np.sin(ph), 0.02 * np.cos(ph)]).tolist()


def time_model(model, n_calls, repeat=3):
    """Best of ``repeat`` passes over the orbit, µs per call; plus the mean hybrid iterations."""
    states = orbit(n_calls)
    model.dimensionless(*states[0])  # warm-up: numba compilation, active set, t
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        for s in states:
            model.dimensionless(*s)
        best = min(best, (time.perf_counter() - t0) / n_calls * 1e6)
    return best


def hybrid_iterations(model, n_calls=2048):
    nt = nl = 0
    for s in orbit(n_calls):
        model.dimensionless(*s)
        nt += model.last_info["t_iterations"]
        nl += model.last_info["lcp_iterations"]
    return nt / n_calls, nl / n_calls


def main():
    b = BearingData(diameter=0.070, length=0.050, clearance=150e-6, viscosity=0.0288)
    print(f"machine: {platform.machine()}, {platform.python_implementation()} "
          f"{platform.python_version()}; orbit around eps 0.6, L/D {b.lambda_:.3f}")
    rows = [("hybrid n=192", lambda: HybridBearing(b, n=192), 20000, 3),
            ("hybrid n=384", lambda: HybridBearing(b, n=384), 10000, 3)]
    rows.append(("short bearing (Ocvirk)", ShortBearing and (lambda: ShortBearing(b)), 20000, 3))
    rows.append(("fd/multigrid 192x32, central Jacobian",
                 FiniteDifferenceBearing and (lambda: FiniteDifferenceBearing(b)), 20, 1))
    rows.append(("fd/multigrid 192x32, forward Jacobian (paper case 4)",
                 FiniteDifferenceBearing and (lambda: FiniteDifferenceBearing(
                     b, jacobian_scheme="forward")), 20, 1))
    ref = None
    for name, make, n_calls, repeat in rows:
        if make is None:
            print(f"{name:55s} not available")
            continue
        model = make()
        us = time_model(model, n_calls, repeat)
        ref = ref or us
        extra = ""
        if isinstance(model, HybridBearing):
            nt, nl = hybrid_iterations(model)
            extra = f"   (mean Newton passes on t {nt:.3f}, active-set passes {nl:.3f})"
        print(f"{name:55s} {us:12.1f} µs/call   x{us / ref:9.1f} vs hybrid n=192{extra}")


if __name__ == "__main__":
    main()
