"""Ready-made objects of the paper's system, built from the shipped case files.

The paper's data (Tables 1-3, Sec. 4.1) live in one place, the case files of
``models`` (``baguet2010_spur``, ``baguet2010_helical``); these factories build physics
objects from them for tests, benchmarks, examples and doctests (the ``*_example()`` pattern of
ROSS), so no module repeats the numbers.

>>> pair = paper_gear_pair()
>>> round(pair.transverse_contact_ratio, 3), round(pair.tip_clearance[0] * 1e3, 2)
(1.721, 1.6)
>>> round(paper_gear_pair(12.5).overlap_ratio, 3)
0.706
"""

from __future__ import annotations

import math

from fmu_src import description
from fmu_src.case import Case, load_case

__all__ = ["helix_overrides", "paper_case", "paper_gear_pair", "paper_structure",
           "paper_system"]

SPUR = "baguet2010_spur"
HELICAL = "baguet2010_helical"


def helix_overrides(helix_angle_deg: float) -> dict:
    """Case overrides turning the spur case into a helical variant of helix angle beta [deg]
    (both gears): the centre distance 366 mm and the transverse module 4 mm are kept, so the
    normal module is ``4 mm cos(beta)`` (the reading of ``baguet2010_helical``; a normal module
    of 4 mm at 12.5 deg would need x1 + x2 = -2.3 to fit 366 mm); for beta > 0 the pinion
    left-hand, the gear right-hand (as ``baguet2010_helical``)."""
    out = {"gears.*.helix_angle": f"{helix_angle_deg} deg",
           "gears.*.module": f"{4.0 * math.cos(math.radians(helix_angle_deg))} mm"}
    if helix_angle_deg > 0.0:
        out |= {"gears.pinion.hand": "left", "gears.gear.hand": "right"}
    return out


def paper_case(helix_angle_deg: float = 0.0, **overrides) -> Case:
    """The paper's spur case (``baguet2010_spur``), or its helical variant for beta > 0
    (:func:`helix_overrides`), with optional ``{"section.name.key": value}`` overrides."""
    if helix_angle_deg:
        overrides = {**helix_overrides(helix_angle_deg), **overrides}
    return load_case(SPUR, overrides or None)


def paper_gear_pair(helix_angle_deg: float = 0.0):
    """The gear pair of Table 1 (:class:`gear_fmu.mesh.geometry.GearPair`)."""
    return description.gear_pairs(paper_case(helix_angle_deg))[0]


def paper_system(helix_angle_deg: float = 0.0, n_elements: int = 8):
    """The two-shaft system of Fig. 1, Tables 1-2 (:class:`gear_fmu.system.GearShaftSystem`),
    each shaft cut into ``n_elements`` elements."""
    length = sum(paper_case()["shafts.pinion_shaft.length"])
    case = paper_case(helix_angle_deg, **{"shafts.*.element_length": length / n_elements})
    return description.gear_shaft_system(case)


def paper_structure(helix_angle_deg: float = 0.0, **overrides):
    """The gear-shaft structure of the paper's case (:class:`gear_fmu.structure.Structure`)."""
    return description.structure(paper_case(helix_angle_deg, **overrides))
