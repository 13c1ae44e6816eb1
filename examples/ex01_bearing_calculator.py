"""Example 1: the hybrid bearing calculator on the paper's pinion bearing (Table 3, Sec. 4.1).

The pinion bearing (D 70 mm, L 50 mm, C 150 um, mu 0.0288 Pa s) at 325 rad/s carries half the
static tooth force, ``T / (2 r_b1)``. The static equilibrium (Eq. 8) gives the journal position,
the eccentricity ratio and the 8 coefficients Kb, Cb (Eq. 18) of the hybrid method (Sec. 2.2.2);
the finite-difference/multigrid solver (Table 4's reference) gives the same position.

Run: ``python examples/ex01_bearing_calculator.py``
"""

from __future__ import annotations

import math

from bearing_fmu import model_class
from bearing_fmu.static import static_equilibrium
from fmu_src import description
from fmu_src.examples import paper_case


def main(model: str = "hybrid") -> dict:
    """Static equilibrium of bearing 1 of the paper's spur case with ``model``."""
    case = paper_case(**{"bearings.*.model": model})
    first = case.names("bearings")[0]
    bearing = description.bearing_data(case)[0]
    omega = description.bearing_speeds(case)[0]
    pair = description.gear_pairs(case)[0]  # the paper's one pair
    load = case["drive.torque"] / pair.base_radius[0] / 2  # N, half the tooth force
    bearing_model = model_class(model).from_parameters(
        bearing, **description.bearing_options(case, first))
    sol = static_equilibrium(bearing_model, (0.0, -load), omega)
    return {"model": model, "load_N": load, "speed_rad_s": omega,
            "sommerfeld": bearing.sommerfeld(omega, load), "eccentricity": sol.eccentricity,
            "attitude_deg": sol.attitude_deg, "x0_m": sol.x0, "y0_m": sol.y0,
            "stiffness_N_per_m": sol.result.stiffness, "damping_N_s_per_m": sol.result.damping}


if __name__ == "__main__":
    for name in ("hybrid", "fd", "short"):
        r = main(name)
        print(f"{name:6s}: load {r['load_N']:.0f} N at {r['speed_rad_s']:.0f} rad/s, Sommerfeld "
              f"{r['sommerfeld']:.4f}: eccentricity {r['eccentricity']:.5f}, attitude "
              f"{r['attitude_deg']:.2f} deg, journal at "
              f"{math.degrees(math.atan2(r['y0_m'], r['x0_m'])):.1f} deg")
        if name == "hybrid":
            print("  Kb [N/m]:", " ".join(f"{v:.4e}" for v in r["stiffness_N_per_m"].ravel()))
            print("  Cb [N s/m]:", " ".join(f"{v:.4e}" for v in r["damping_N_s_per_m"].ravel()))
