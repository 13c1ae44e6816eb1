"""The layout's derived topology and its refusals: every error names the component, the
field and the limit (:class:`gear_fmu.layout.LayoutError`)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from gear_fmu.layout import (
    BearingSpec,
    DiscSpec,
    Drive,
    GearSpec,
    Layout,
    LayoutError,
    MeshSpec,
    ShaftSpec,
)
from gear_fmu.mesh.train import gear_pair

MAT = dict(young=210e9, poisson=0.3, density=7800.0, element_length=0.02)
TOOTH = dict(module=4e-3, pressure_angle=math.radians(20.0), face_width=0.03, mass=1.0)


def shaft(name, length=0.2):
    return ShaftSpec(name, (length,), (0.05,), (0.0,), **MAT)


def bearings(*names, length=0.2):
    return tuple(BearingSpec(f"{s}{k}", s, p, "lumped", 0.05, 0.02, 50e-6, 0.02)
                 for s in names for k, p in ((1, 0.0), (2, length)))


def idler_train(**changes):
    """a -> idler -> c: one gear in two meshes, the output turning as the input."""
    gears = (GearSpec("g1", "a", 0.1, 20, **TOOTH), GearSpec("gi", "i", 0.1, 31, **TOOTH),
             GearSpec("g3", "c", 0.1, 40, **TOOTH))
    meshes = (MeshSpec("m1", ("g1", "gi"), 0.102), MeshSpec("m2", ("gi", "g3"), 0.142,
                                                             direction=math.radians(120.0)))
    parts = dict(shafts=(shaft("a"), shaft("i"), shaft("c")), gears=gears, meshes=meshes,
                 bearings=bearings("a", "i", "c"), drive=Drive("a", "c", 100.0, 50.0))
    parts.update(changes)
    return Layout(**parts)


def test_speeds_directions_and_centres_follow_the_gear_graph():
    lay = idler_train()
    np.testing.assert_allclose(lay.speeds, [100.0, -100.0 * 20 / 31, 100.0 * 20 / 40])
    assert lay.directions.tolist() == [1, -1, 1]
    assert lay.drivers == (("g1", "gi"), ("gi", "g3"))
    c = lay.shaft_centres
    np.testing.assert_allclose(c[1], [0.102, 0.0])
    np.testing.assert_allclose(np.linalg.norm(c[2] - c[1]), 0.142)
    assert lay.torque_on("c") == pytest.approx(50.0 * 40 / 20)


def test_a_speed_increaser_drives_from_its_big_gear():
    """The driver is the gear on the input side, whatever its size."""
    gears = (GearSpec("big", "a", 0.1, 60, **TOOTH), GearSpec("small", "b", 0.1, 20, **TOOTH))
    lay = Layout((shaft("a"), shaft("b")), gears, (MeshSpec("m", ("small", "big"), 0.16),),
                 bearings("a", "b"), Drive("a", "b", 100.0, 50.0))
    assert lay.drivers == (("big", "small"),)
    assert lay.speeds[1] == pytest.approx(-300.0)
    assert gear_pair(lay, 0).teeth == (60, 20)


@pytest.mark.parametrize("change, words", [
    (dict(gears=(GearSpec("g1", "a", 0.1, 20, **TOOTH), GearSpec("gi", "i", 0.1, 31, **TOOTH),
                 GearSpec("g3", "c", 0.1, 40, **TOOTH), GearSpec("g5", "a", 0.15, 20, **TOOTH),
                 GearSpec("g6", "c", 0.15, 20, **TOOTH)),
          meshes=(MeshSpec("m1", ("g1", "gi"), 0.102), MeshSpec("m2", ("gi", "g3"), 0.142),
                  MeshSpec("m3", ("g6", "g5"), 0.08))),
     "closed loop"),
    (dict(meshes=(MeshSpec("m1", ("g1", "gi"), 0.102),)), "in no mesh"),
    (dict(gears=(GearSpec("g1", "a", 0.1, 20, **TOOTH), GearSpec("gi", "i", 0.1, 31, **TOOTH),
                 GearSpec("g3", "i", 0.05, 40, **TOOTH))), "both on shaft i"),
    (dict(drive=Drive("a", "x", 100.0, 50.0)), "drive.output_shaft = 'x': no such shaft"),
    (dict(gears=(GearSpec("g1", "a", 0.25, 20, **TOOTH), GearSpec("gi", "i", 0.1, 31, **TOOTH),
                 GearSpec("g3", "c", 0.1, 40, **TOOTH))), "outside its shaft a"),
    (dict(gears=(GearSpec("g1", "a", 0.01, 20, **TOOTH), GearSpec("gi", "i", 0.1, 31, **TOOTH),
                 GearSpec("g3", "c", 0.1, 40, **TOOTH))), "overlap on shaft a"),
    (dict(gears=(GearSpec("g1", "q", 0.1, 20, **TOOTH), GearSpec("gi", "i", 0.1, 31, **TOOTH),
                 GearSpec("g3", "c", 0.1, 40, **TOOTH))), "gears.g1.shaft = 'q': no such shaft"),
    (dict(meshes=(MeshSpec("m1", ("g1", "gx"), 0.102), MeshSpec("m2", ("gi", "g3"), 0.142))),
     "meshes.m1.gears = 'gx': no such gear"),
    (dict(bearings=bearings("a", "i", "c")[:-1]), "shaft c has 1 bearing"),
    (dict(drive=Drive("a", "i", 100.0, 50.0)), "mesh m2 is not between the input shaft a"),
])
def test_a_train_that_cannot_be_modelled_is_refused_with_its_names(change, words):
    with pytest.raises(LayoutError, match=words):
        idler_train(**change)


def test_two_separate_trains_are_refused():
    lay = idler_train()
    gears = (*lay.gears, GearSpec("h1", "x", 0.1, 20, **TOOTH), GearSpec("h2", "y", 0.1, 20,
                                                                          **TOOTH))
    meshes = (*lay.meshes, MeshSpec("mx", ("h1", "h2"), 0.08))
    with pytest.raises(LayoutError, match="not joined to the input shaft a"):
        dataclasses.replace(lay, shafts=(*lay.shafts, shaft("x"), shaft("y")), gears=gears,
                            meshes=meshes, bearings=(*lay.bearings, *bearings("x", "y")))


def test_a_disc_on_a_gear_face_is_refused():
    with pytest.raises(LayoutError, match=r"gear g1 .* and disc hub .* overlap on shaft a"):
        idler_train(discs=(DiscSpec("hub", "a", 0.1, 1.0),))


def test_gears_of_a_mesh_must_share_module_and_opposite_hands():
    with pytest.raises(LayoutError, match=r"gears\.g1\.module = 3 mm and gears\.gi\.module "
                                          r"= 4 mm differ"):
        idler_train(gears=(GearSpec("g1", "a", 0.1, 20, **{**TOOTH, "module": 3e-3}),
                           GearSpec("gi", "i", 0.1, 31, **TOOTH),
                           GearSpec("g3", "c", 0.1, 40, **TOOTH)))
    helical = dict(helix_angle=math.radians(10.0), hand="left")
    with pytest.raises(LayoutError, match="both 'left'"):
        idler_train(gears=(GearSpec("g1", "a", 0.1, 20, **TOOTH, **helical),
                           GearSpec("gi", "i", 0.1, 31, **TOOTH, **helical),
                           GearSpec("g3", "c", 0.1, 40, **TOOTH)))


def test_a_helical_gear_needs_its_hand():
    with pytest.raises(LayoutError, match=r"gears\.g1: a helical gear .* needs its hand"):
        GearSpec("g1", "a", 0.1, 20, helix_angle=0.2, **TOOTH)
