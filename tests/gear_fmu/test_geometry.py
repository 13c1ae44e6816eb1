"""Gear geometry of Table 1: contact ratios against closed forms and hand values, bad input."""

import math

import pytest

from fmu_src.examples import paper_gear_pair
from gear_fmu.mesh.geometry import GearGeometryError, GearPair, involute

DEG = math.pi / 180


def table1(**kw):
    data = dict(teeth=(26, 157), module=4e-3, pressure_angle=20 * DEG, centre_distance=0.366,
                face_width=(0.050, 0.040), profile_shift=(0.16, -0.16),
                addendum_coefficient=1.0, dedendum_coefficient=1.4)
    data.update(kw)
    return GearPair(**data)


def test_table1_spur_pair_by_hand():
    """Radii and the transverse contact ratio worked out by hand from ISO 21771 (x1 + x2 = 0, so
    a = 366 mm is the reference centre distance and alpha' = 20 deg)."""
    g = table1()
    assert g.pitch_radius == pytest.approx((0.052, 0.314), abs=1e-15)
    assert g.tip_radius == pytest.approx((0.05664, 0.31736), abs=1e-12)
    assert g.root_radius == pytest.approx((0.04704, 0.30776), abs=1e-12)
    assert math.degrees(g.operating_pressure_angle) == pytest.approx(20.0, abs=1e-9)
    assert g.backlash == pytest.approx(0.0, abs=1e-12)
    rb1, rb2 = 0.052 * math.cos(20 * DEG), 0.314 * math.cos(20 * DEG)
    eps = (math.sqrt(0.05664**2 - rb1**2) + math.sqrt(0.31736**2 - rb2**2)
           - 0.366 * math.sin(20 * DEG)) / (math.pi * 4e-3 * math.cos(20 * DEG))
    assert g.transverse_contact_ratio == pytest.approx(eps, rel=1e-12)
    assert g.transverse_contact_ratio == pytest.approx(1.7206, abs=1e-4)
    assert g.overlap_ratio == 0.0
    print("\n" + g.summary())


def test_helical_overlap_ratio_against_the_normal_section_formula():
    """epsilon_beta = b sin(beta) / (pi m_n) (ISO 21771), computed here without beta_b."""
    for beta in (5.0, 12.5, 20.0):
        g = paper_gear_pair(beta)
        assert g.overlap_ratio == pytest.approx(
            0.040 * math.sin(beta * DEG) / (math.pi * g.module), rel=1e-12)
        # the transverse geometry of the spur pair is kept (module docstring)
        assert g.transverse_module == pytest.approx(4e-3, rel=1e-14)
        assert g.backlash == pytest.approx(0.0, abs=1e-12)


def tight_mesh(teeth, x, module=4e-3, alpha=20 * DEG):
    """Operating angle and centre distance without backlash, from the involute function equation
    inv(a') = inv(alpha) + 2 tan(alpha) (x1 + x2) / (z1 + z2) (spur)."""
    aw = alpha
    target = involute(alpha) + 2 * math.tan(alpha) * sum(x) / sum(teeth)
    for _ in range(60):  # Newton on inv(a') = target
        aw -= (involute(aw) - target) / math.tan(aw) ** 2
    return aw, 0.5 * module * sum(teeth) * math.cos(alpha) / math.cos(aw)


def test_profile_shift_sets_the_operating_pressure_angle():
    """With x1 + x2 > 0 at the tight-mesh centre distance the backlash is zero."""
    x = (0.3, 0.2)
    aw, a = tight_mesh((26, 157), x)
    g = table1(profile_shift=x, centre_distance=a, dedendum_coefficient=1.25)
    assert g.operating_pressure_angle == pytest.approx(aw, rel=1e-12)
    assert abs(g.backlash) < 1e-12
    with pytest.raises(GearGeometryError, match="overlap"):
        table1(profile_shift=x, centre_distance=a - 1e-5, dedendum_coefficient=1.25)


@pytest.mark.parametrize("kw,message", [
    # Table 1 read literally (addendum 1.4): the pinion tips cut 1.6 mm into the gear root
    (dict(addendum_coefficient=1.4, dedendum_coefficient=1.0), "cut 1.600 mm into"),
    (dict(centre_distance=0.3655), "overlap"),
    (dict(teeth=(12, 157), centre_distance=0.338, profile_shift=(-0.3, 0.3)), "undercut"),
    (dict(teeth=(26, 157), centre_distance=0.31), "base radii"),
    (dict(module=-4e-3), "module"),
    (dict(teeth=(26.5, 157)), "teeth"),
])
def test_bad_geometry_is_rejected_with_the_numbers(kw, message):
    with pytest.raises(GearGeometryError, match=message):
        table1(**kw)


def test_tip_to_root_interference_is_detected():
    """A small pinion with a strongly negative centre-distance modification: the gear tips
    reach below the start of the pinion's generated involute (not undercut itself)."""
    x = (0.2, -0.6)
    _, a = tight_mesh((14, 60), x)
    with pytest.raises(GearGeometryError, match="tip-to-root interference"):
        GearPair((14, 60), 4e-3, 20 * DEG, a, (0.04, 0.04), profile_shift=x,
                 dedendum_coefficient=1.4)
    # the same pair without the gear's negative shift meshes
    _, a = tight_mesh((14, 60), (0.2, 0.0))
    GearPair((14, 60), 4e-3, 20 * DEG, a, (0.04, 0.04), profile_shift=(0.2, 0.0),
             dedendum_coefficient=1.4)
