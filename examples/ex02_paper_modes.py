"""Example 2: the natural modes of the paper's gear-shaft system (Fig. 1, Tables 1-3).

Two configurations:

* the shafts alone on stiff bearings (no mesh): the gear shaft's bending mode, to compare with
  a Rayleigh estimate (gear disc at mid-span of a simply supported Timoshenko shaft);
* the whole system as ``gsb modal`` sees it: the mean mesh stiffness at the static load and the
  bearings' film stiffness at the static solution X0 (symmetric part of Kb).

Run: ``python examples/ex02_paper_modes.py``
"""

from __future__ import annotations

import math

import numpy as np

import orchestrator as gsb
from fmu_src.examples import paper_system
from gear_fmu.modal.modes import mode_table, natural_modes

STIFF = 1e12  # N/m, "stiff" bearings


def gear_translation_mode(system, found) -> float:
    """Lowest mode where the gear body's translation holds most of the kinetic energy [rad/s]."""
    node = int(system.gear_nodes[1])  # the gear's node: u, v its first two DOFs
    g = [6 * node, 6 * node + 1]
    share = system.layout.gears[1].mass * (found.shapes[g] ** 2).sum(axis=0)
    return float(found.omega[share > 0.5][0])


def rayleigh_gear_translation(system) -> float:
    """k = 1 / (L^3/(48 EI) + L/(4 kGA)), m = M_gear + 17/35 m_shaft [rad/s]."""
    shaft = system.layout.shafts[1]
    s, length = shaft.section(0), shaft.length  # the paper's shafts: one segment each
    k = 1.0 / (length**3 / (48.0 * s.young * s.second_moment)
               + length / (4.0 * s.shear_coefficient * s.shear_modulus * s.area))
    return math.sqrt(k / (system.layout.gears[1].mass + 17.0 / 35.0 * shaft.mass))


def main(n_modes: int = 12) -> dict:
    system = paper_system()
    stiff = natural_modes(system, STIFF)
    full = gsb.modes("baguet2010_spur").modes  # with the bearings' film at X0
    mesh_mode = int(np.argmax(full.mesh_energy_fraction))
    return {"gear_translation_hz": gear_translation_mode(system, stiff) / (2 * math.pi),
            "rayleigh_hz": rayleigh_gear_translation(system) / (2 * math.pi),
            "modes": full, "table": mode_table(full, n_modes),
            "mesh_mode_hz": float(full.frequency_hz[mesh_mode]),
            "mesh_mode_fraction": float(full.mesh_energy_fraction[mesh_mode])}


if __name__ == "__main__":
    r = main()
    print(f"stiff bearings, no mesh: gear translation mode {r['gear_translation_hz']:.1f} Hz "
          f"(Rayleigh estimate {r['rayleigh_hz']:.1f} Hz)")
    print("with the mean mesh stiffness and the bearings' film stiffness at X0:")
    print(r["table"])
    print(f"mesh-dominated mode: {r['mesh_mode_hz']:.1f} Hz ({100 * r['mesh_mode_fraction']:.0f} "
          "% of its strain energy in the mesh)")
