"""Microseconds per coupled step of the paper's spur case as its bearings and contact slices grow.

Usage: ``python benchmarks/scaling.py [--periods N] [--slices N ...]``

Issue 44's item 6 asks that the cost of a step grow at most linearly with the bearings and
the contact slices. In-process, warm caches, each configuration after a warm-up run:

* the mesh's slices across the face width (``meshes.mesh.slices``, default 20) at each of
  ``--slices``, linear bearings (the structure's step alone: the mesh evaluation and the
  contact loop are what the slices change);
* the four bearings of the paper, then eight: bearings 5 to 8 at a quarter and three quarters
  of each shaft (:func:`eight_bearings`; two more bearing nodes per shaft, so 20 -> 28
  condensed DOFs), hybrid bearings (their evaluation dominates a step) and linear ones.

Prints microseconds per step and the ratio to the first configuration of each series beside
the ratio of the counts.
"""

from __future__ import annotations

import argparse
import platform
import tempfile
from pathlib import Path

from fmu_src.case import load_case, shipped_cases
from orchestrator.run.runner import run_case

#: bearings 5-8 (a copy of bearing 1's or 3's data at another position), TOML
EXTRA = """
[bearings.{name}]
shaft = "{shaft}"
position = "{position} mm"
model = "hybrid"
diameter = "{diameter} mm"
length = "{length} mm"
clearance = "{clearance} um"
viscosity = "{viscosity} Pa.s"
nodes = 192
"""


def eight_bearings(folder: Path) -> Path:
    """The paper's spur case file with bearings 5-8 added at nodes between the end bearings
    and the gears (Table 3's diameter and clearance of their shaft, shorter to fit there: 20
    and 14 mm; the gear shaft's with a thicker oil, 0.1 Pa s, to carry their share)."""
    text = shipped_cases()["baguet2010_spur"].read_text()
    for name, shaft, position, d, length, c, mu in (
            (5, "pinion_shaft", 40, 70, 20, 150, 0.0288),
            (6, "pinion_shaft", 120, 70, 20, 150, 0.0288),
            (7, "gear_shaft", 40, 90, 14, 110, 0.1), (8, "gear_shaft", 120, 90, 14, 110, 0.1)):
        text += EXTRA.format(name=name, shaft=shaft, position=position, diameter=d,
                             length=length, clearance=c, viscosity=mu)
    path = folder / "eight_bearings.toml"
    path.write_text(text.replace('name = "baguet2010_spur"', 'name = "eight_bearings"'))
    return path


def per_step(case, periods: int, folder: str) -> float:
    """Microseconds per coupled step of ``case`` in-process over ``periods`` mesh periods."""
    run_case(case.with_overrides({"simulation.mesh_periods": 2}), in_process=True,
             out_dir=folder, progress=False)  # warm-up: numba's cache, the condensations
    s = run_case(case.with_overrides({"simulation.mesh_periods": periods}), in_process=True,
                 out_dir=folder, progress=False)
    return 1e6 * s.wall_time / s.steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--periods", type=int, default=256)
    parser.add_argument("--slices", type=int, nargs="+", default=[10, 20, 40, 80])
    args = parser.parse_args()
    print(f"machine: {platform.machine()}, CPython {platform.python_version()}; "
          f"baguet2010_spur in-process, {args.periods} mesh periods")
    with tempfile.TemporaryDirectory() as tmp:
        first = None
        for n in args.slices:
            case = load_case("baguet2010_spur", {"bearings.*.model": "linear",
                                                 "meshes.mesh.slices": n})
            us = per_step(case, args.periods, f"{tmp}/slices{n}")
            first = first or (n, us)
            print(f"slices {n:4d}, linear bearings: {us:8.1f} us/step  x{us / first[1]:5.2f} "
                  f"for x{n / first[0]:5.2f} slices")
        eight = eight_bearings(Path(tmp))
        for model in ("hybrid", "linear"):
            four = per_step(load_case("baguet2010_spur", {"bearings.*.model": model}),
                            args.periods, f"{tmp}/four_{model}")
            more = per_step(load_case(eight, {"bearings.*.model": model}), args.periods,
                            f"{tmp}/eight_{model}")
            print(f"{model:6s} bearings, 4 -> 8: {four:8.1f} -> {more:8.1f} us/step  "
                  f"x{more / four:5.2f} for x2 bearings")


if __name__ == "__main__":
    main()
