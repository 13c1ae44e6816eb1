"""µs per force + Jacobian call of the bearing models, after numba warm-up.

    python benchmarks/bearing_models.py

The states follow an orbit of radius 0.05 C around eccentricity 0.6 (L/D 0.714, the paper's
pinion bearing), with velocities, 1,024 calls per orbit as in the paper's time-stepping run
(warm starts). Ratios
are against the hybrid n = 192 measured in the same process.
"""

import math
import platform
import time

import numpy as np

from bearing_fmu import BearingData
from bearing_fmu.fd import FiniteDifferenceBearing
from bearing_fmu.hybrid import HybridBearing
from bearing_fmu.short_bearing import ShortBearing


def orbit(n_calls):
    k = np.arange(n_calls)
    # 1024 calls per orbit: the paper's run takes 65,536 steps for ~60 pinion revolutions,
    # i.e. ~1,100 steps per unbalance orbit
    ph = 2 * math.pi * k / 1024.0
    return np.column_stack([0.6 + 0.05 * np.cos(ph), 0.05 * np.sin(ph),
                            -0.02 * np.sin(ph), 0.02 * np.cos(ph)])


def time_model(model, n_calls):
    states = orbit(n_calls)
    model.dimensionless(*states[0])  # warm-up: numba compilation, active set, t
    t0 = time.perf_counter()
    for s in states:
        model.dimensionless(*s)
    return (time.perf_counter() - t0) / n_calls * 1e6


def main():
    b = BearingData(diameter=0.070, length=0.050, clearance=150e-6, viscosity=0.0288)
    rows = [
        ("hybrid n=192", HybridBearing(b, n=192), 20000),
        ("hybrid n=384", HybridBearing(b, n=384), 10000),
        ("short bearing", ShortBearing(b), 20000),
        ("fd/multigrid 192x32 (central Jacobian)", FiniteDifferenceBearing(b), 20),
        ("fd/multigrid 192x32 (forward Jacobian, paper case 4)",
         FiniteDifferenceBearing(b, jacobian_scheme="forward"), 20),
    ]
    print(f"machine: {platform.machine()}, {platform.python_implementation()} "
          f"{platform.python_version()}")
    ref = None
    for name, model, n in rows:
        us = time_model(model, n)
        ref = ref or us
        print(f"{name:55s} {us:12.1f} µs/call   x{us / ref:9.1f} vs hybrid n=192")


if __name__ == "__main__":
    main()
