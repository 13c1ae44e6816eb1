"""Case files: every shipped case loads in SI and builds its gear train; the paper's cases equal
their single-stage files of earlier versions; bad input fails early with one line naming the
field, the value and the limit."""

import math
import warnings

import pytest

from fmu_src import description
from fmu_src.case import (
    FIELDS,
    CaseError,
    LegacyCaseWarning,
    load_case,
    parse_case,
    parse_toml,
    schema_markdown,
    shipped_cases,
)
from tests.helpers import ROOT

SPUR = shipped_cases()["baguet2010_spur"]

#: the paper's spur case as the single-stage schema wrote it (models/baguet2010_spur.toml before
#: the train schema), the translator's input
OLD_SPUR = """
[case]
name = "baguet2010_spur"
description = "Single-stage spur gear, two shafts, four hydrodynamic bearings (paper Sec. 4.1)"

[gear_pair]                       # Table 1
teeth = [26, 157]
module = "4 mm"
pressure_angle = "20 deg"
helix_angle = "0 deg"
profile_shift = [0.16, -0.16]
addendum_coefficient = 1.0
dedendum_coefficient = 1.4
face_width = ["50 mm", "40 mm"]
centre_distance = "366 mm"
mass = ["2 kg", "74 kg"]

[shafts]                          # Table 2
outer_diameter = ["70 mm", "90 mm"]
inner_diameter = ["30 mm", "30 mm"]
length = "160 mm"
young_modulus = "210000 MPa"
poisson_ratio = 0.3
density = "7800 kg/m^3"
elements = 8

[bearings]                        # Table 3; order: 1, 2 (pinion shaft), 3, 4 (gear shaft)
model = "hybrid"
diameter = ["70 mm", "70 mm", "90 mm", "90 mm"]
length = ["50 mm", "50 mm", "65 mm", "65 mm"]
clearance = ["150 um", "150 um", "110 um", "110 um"]
viscosity = "0.0288 Pa.s"
nodes = 192

[operation]                       # Sec. 4.1
speed = "325 rad/s"
torque = "220 N.m"
unbalance = ["0.6 mm", "0.6 mm"]

[simulation]                      # Sec. 4
damping_ratio = 0.03
steps_per_mesh_period = 32
mesh_periods = 2048
tolerance = 1e-5
"""


def old_file(tmp_path, text=OLD_SPUR, name="old_spur.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def load_old(path, overrides=None):
    with pytest.warns(LegacyCaseWarning, match="single-stage case file.*docs/case-files.md"):
        return load_case(path, overrides)


def test_paper_spur_case_in_si_units():
    c = load_case(SPUR)
    assert c["gears.pinion.module"] == pytest.approx(4e-3)
    assert c["gears.gear.pressure_angle"] == pytest.approx(math.radians(20.0))
    assert [c[f"bearings.{b}.clearance"] for b in c.names("bearings")] == pytest.approx(
        [150e-6, 150e-6, 110e-6, 110e-6])
    assert c["shafts.pinion_shaft.young_modulus"] == pytest.approx(210e9)
    assert c["shafts.gear_shaft.outer_diameter"] == pytest.approx([0.09])
    assert c["gears.pinion.unbalance"] == pytest.approx(0.6e-3)
    assert c["drive.speed"] == 325.0 and c["simulation.mesh_periods"] == 2048
    assert c.names("shafts") == ["pinion_shaft", "gear_shaft"]
    assert c.names("bearings") == ["1", "2", "3", "4"]
    assert c.names("discs") == []


@pytest.mark.parametrize("name", sorted(shipped_cases()))
def test_every_shipped_case_loads_builds_and_round_trips(name):
    """Each shipped case loads by name, builds its layout and one gear pair per mesh, and its
    to_toml() reloads to the same values, bit for bit (same types, same order)."""
    c = load_case(name)
    lay = description.layout(c)
    pairs = description.gear_pairs(c)
    assert len(pairs) == len(lay.meshes) == len(c.names("meshes")) >= 1
    assert [b.name for b in lay.bearings] == c.names("bearings")
    again = parse_case(parse_toml(c.to_toml(), "round trip"), "round trip")
    assert list(again.values) == list(c.values)
    for key, value in c.values.items():
        assert type(again[key]) is type(value) and again[key] == value, key
    assert again.to_toml(header=False) == c.to_toml(header=False)


def test_new_cases_are_realistic_trains():
    """The two shipped trains: contact ratios above 1.2, positive backlash, the ratio and the
    mixed bearing models the files state."""
    two = load_case("two_stage_reducer")
    lay = description.layout(two)
    assert len(lay.shafts) == 3 and len(lay.meshes) == 2 and len(lay.bearings) == 6
    assert 10.0 <= lay.ratios[0] / lay.ratios[-1] <= 15.0
    assert {two[f"bearings.{b}.model"] for b in two.names("bearings")} == {"hybrid", "short"}
    assert description.shared_bearing_model(two) is None
    assert two.names("discs") == ["coupling_hub"]
    assert lay.meshes[1].direction == pytest.approx(math.radians(30.0))
    over = load_case("overhung_pinion")
    lay_o = description.layout(over)
    pinion, bearings = lay_o.gear("pinion"), [b for b in lay_o.bearings
                                              if b.shaft == "pinion_shaft"]
    assert all(b.position < pinion.position for b in bearings)  # overhung
    for case in (two, over):
        for pair in description.gear_pairs(case):
            assert pair.transverse_contact_ratio > 1.2 and pair.backlash > 0.0


def test_paper_cases_equal_their_single_stage_files(tmp_path):
    """The translated single-stage spur file gives every value of the shipped spur case."""
    old = load_old(old_file(tmp_path))
    new = load_case(SPUR)
    assert list(old.values) == list(new.values)
    for key, value in new.values.items():
        assert type(old[key]) is type(value) and old[key] == value, key


def test_single_stage_translation(tmp_path):
    """Helical hands, gravity, the model for every bearing, and overrides with the old keys
    applied before the translation (new keys after it)."""
    text = OLD_SPUR.replace('helix_angle = "0 deg"', 'helix_angle = "12.5 deg"').replace(
        'module = "4 mm"', 'module = "3.9051840284797 mm"').replace(
        'unbalance = ["0.6 mm", "0.6 mm"]', 'unbalance = ["0.6 mm", "0.3 mm"]\ngravity = true')
    c = load_old(old_file(tmp_path, text),
                 {"bearings.model": "linear", "operation.speed": "300 rad/s",
                  "bearings.2.clearance": "160 um"})
    assert (c["gears.pinion.hand"], c["gears.gear.hand"]) == ("left", "right")
    assert c["gears.gear.unbalance"] == pytest.approx(0.3e-3)
    assert c["gears.gear.unbalance_mass"] == "shaft"
    assert c["drive.gravity"] == [0.0, -9.81]
    assert {c[f"bearings.{b}.model"] for b in c.names("bearings")} == {"linear"}
    assert c["drive.speed"] == 300.0 and c["bearings.2.clearance"] == pytest.approx(160e-6)
    assert c["shafts.gear_shaft.element_length"] == pytest.approx(0.02)


def test_old_keys_on_a_current_file_name_the_new_key():
    with pytest.raises(CaseError, match=r"operation\.speed is a field of the single-stage "
                                        r"schema.*now drive\.speed"):
        load_case(SPUR, {"operation.speed": "300 rad/s"})
    with pytest.raises(CaseError, match=r"bearings\.model .*now bearings\.\*\.model"):
        load_case(SPUR).with_overrides({"bearings.model": "short"})


def test_wildcard_and_named_overrides():
    c = load_case(SPUR, {"bearings.*.model": "short", "gears.*.unbalance": "1.2 mm",
                         "bearings.3.clearance": "120 um"})
    assert [c[f"bearings.{b}.model"] for b in c.names("bearings")] == ["short"] * 4
    assert c["gears.pinion.unbalance"] == c["gears.gear.unbalance"] == pytest.approx(1.2e-3)
    assert c["bearings.3.clearance"] == pytest.approx(120e-6)
    assert c["bearings.4.clearance"] == pytest.approx(110e-6)
    c2 = load_case(SPUR).with_overrides({"drive.speed": "1000 rpm",
                                         "shafts.*.outer_diameter": "80 mm"})
    assert c2["drive.speed"] == pytest.approx(1000 * 2 * math.pi / 60)
    assert c2["shafts.gear_shaft.outer_diameter"] == pytest.approx([0.08])  # one per segment
    c3 = load_case("two_stage_reducer", {"bearings.out_a.model": "hybrid"})
    assert c3["bearings.out_a.model"] == "hybrid" and c3["bearings.out_b.model"] == "short"
    with pytest.raises(CaseError, match=r"no bearing '7'.*bearings: 1, 2, 3, 4"):
        load_case(SPUR, {"bearings.7.clearance": "120 um"})
    with pytest.raises(CaseError, match=r"no gear 'pinon'; did you mean pinion\?"):
        load_case(SPUR).with_overrides({"gears.pinon.unbalance": 0.0})
    with pytest.raises(CaseError, match=r"the case has no discs"):
        load_case(SPUR, {"discs.*.unbalance": "1 mm"})


def test_model_options_come_from_the_registered_models():
    """bearings.*.<option> fields exist for every option a registered model declares, and each
    bearing's own model's bounds apply (hybrid needs at least 16 nodes, fd 8)."""
    from bearing_fmu import MODELS, model_class

    keys = {f.key for f in FIELDS}
    for name in MODELS:
        for opt in model_class(name).options:
            assert f"bearings.*.{opt.key}" in keys
    c = load_case(SPUR, {"bearings.4.model": "fd", "bearings.4.nodes": 8})
    assert c["bearings.4.nodes"] == 8 and c["bearings.3.nodes"] == 192
    with pytest.raises(CaseError, match=r"bearings\.2\.nodes = 8: the hybrid model needs >= 16"):
        load_case(SPUR, {"bearings.2.nodes": 8})


# ------------------------------------------------------------------ bad input, one line each
def write(tmp_path, replace=(), append="", name="case.toml", base=SPUR):
    src = base.read_text() if hasattr(base, "read_text") else base
    for old, new in replace:
        assert old in src, old
        src = src.replace(old, new, 1)
    p = tmp_path / name
    p.write_text(src + append)
    return p


TWO = shipped_cases()["two_stage_reducer"]


@pytest.mark.parametrize("edit,match", [
    # a unit of the wrong kind, an unknown unit
    (dict(replace=[('clearance = "150 um"', 'clearance = "150 N"')]),
     r"bearings\.1\.clearance: '150 N' is a force, expected a length: a number and one of "
     r"the units m, mm, um, µm, cm, e\.g\. '0\.5 m'$"),  # not '150 m': 150 meant in um
    (dict(replace=[("tolerance = 1e-5", 'tolerance = "abc"')]),
     r"simulation\.tolerance: cannot read 'abc' as a number, e\.g\. '0\.5'$"),
    (dict(replace=[('"325 rad/s"', '"325 furlongs"')]), r"drive\.speed: unknown unit"),
    # unknown keys and choices, the closest as a hint
    (dict(replace=[('model = "hybrid"', 'model = "magic"')]),
     r"bearings\.1\.model: 'magic' is not one of"),
    (dict(replace=[("poisson_ratio = 0.3", "poisson_ration = 0.3")]),
     r"unknown field shafts\.pinion_shaft\.poisson_ration; did you mean "
     r"shafts\.pinion_shaft\.poisson_ratio\?"),
    (dict(append="\n[bearing.5]\nshaft = 'gear_shaft'\n"),
     r"unknown section \[bearing\]; did you mean \[bearings\]\?"),
    # a speed at a shaft or a gear
    (dict(replace=[('position = "80 mm"                # mid-span',
                    'position = "80 mm"\nspeed = "300 rad/s"')]),
     r"unknown field gears\.pinion\.speed: the speed is set once, at drive\.speed"),
    (dict(replace=[('element_length = "20 mm"          # 8 elements',
                    'element_length = "20 mm"\nspeed = "300 rad/s"')]),
     r"unknown field shafts\.pinion_shaft\.speed: the speed is set once.*gear ratios"),
    # missing fields, bounds, shapes
    (dict(replace=[('module = "4 mm"\n', "")]), r"missing field gears\.pinion\.module"),
    (dict(replace=[("tolerance = 1e-5", "tolerance = -1")]), r"simulation\.tolerance = -1"),
    (dict(replace=[('outer_diameter = "70 mm"', 'outer_diameter = ["70 mm", "60 mm"]')]),
     r"shafts\.pinion_shaft\.outer_diameter: expected 1 values \(one per length value\)"),
    (dict(replace=[('inner_diameter = "30 mm"', 'inner_diameter = "80 mm"')]),
     r"shafts\.pinion_shaft\.inner_diameter\[1\] = 0\.08 m must be smaller than "
     r"outer_diameter\[1\] = 0\.07 m"),
    # unknown names, the closest as a hint
    (dict(replace=[('shaft = "gear_shaft"\nposition = "80 mm"',
                    'shaft = "gear_shaf"\nposition = "80 mm"')]),
     r"gears\.gear\.shaft = 'gear_shaf': no such shaft; did you mean gear_shaft\? "
     r"\(shafts: pinion_shaft, gear_shaft\)"),
    (dict(replace=[('gears = ["pinion", "gear"]', 'gears = ["pinion", "gears"]')]),
     r"meshes\.mesh\.gears = 'gears': no such gear; did you mean gear\?"),
    (dict(replace=[('input_shaft = "pinion_shaft"', 'input_shaft = "pinion"')]),
     r"drive\.input_shaft = 'pinion': no such shaft; did you mean pinion_shaft\?"),
    # places on a shaft
    (dict(replace=[('position = "80 mm"                # mid-span',
                    'position = "170 mm"')]),
     r"gears\.pinion\.position = 170 mm lies outside its shaft pinion_shaft \(0 to 160 mm\)"),
    (dict(replace=[('[bearings.2]\nshaft = "pinion_shaft"\nposition = "160 mm"',
                    '[bearings.2]\nshaft = "pinion_shaft"\nposition = "90 mm"')]),
     r"gear pinion \(55 to 105 mm\) and bearing 2 \(65 to 115 mm\) overlap on shaft "
     r"pinion_shaft"),
    (dict(append="\n[discs.hub]\nshaft = 'gear_shaft'\nposition = '80 mm'\nmass = '1 kg'\n"),
     r"gear gear \(60 to 100 mm\) and disc hub \(80 to 80 mm\) overlap on shaft gear_shaft"),
    # fewer than two bearings on a shaft
    (dict(replace=[('[bearings.4]\nshaft = "gear_shaft"\nposition = "160 mm"\nmodel = "hybrid"'
                    '\ndiameter = "90 mm"\nlength = "65 mm"',
                    '[bearings.4]\nshaft = "pinion_shaft"\nposition = "120 mm"\nmodel = "hybrid"'
                    '\ndiameter = "90 mm"\nlength = "20 mm"')]),
     r"shaft gear_shaft has 1 bearing: at least two hold a shaft radially"),
    # the gear pair
    (dict(replace=[('centre_distance = "366 mm"', 'centre_distance = "360 mm"')]),
     r"meshes\.mesh \(gears pinion and gear: centre_distance = 360\.000 mm.*the gears mesh "
     r"without backlash at meshes\.mesh\.centre_distance = 366\.000 mm"),
    (dict(replace=[('teeth = 157\nmodule = "4 mm"', 'teeth = 157\nmodule = "5 mm"')]),
     r"meshes\.mesh: gears\.pinion\.module = 4 mm and gears\.gear\.module = 5 mm differ: the "
     r"two gears of a mesh share module, pressure_angle"),
    (dict(replace=[('teeth = 26\nmodule = "4 mm"\npressure_angle = "20 deg"',
                    'teeth = 26\nmodule = "4 mm"\npressure_angle = "20 deg"\n'
                    'helix_angle = "10 deg"\nhand = "left"'),
                   ('teeth = 157\nmodule = "4 mm"\npressure_angle = "20 deg"',
                    'teeth = 157\nmodule = "4 mm"\npressure_angle = "20 deg"\n'
                    'helix_angle = "10 deg"\nhand = "left"')]),
     r"gears\.pinion\.hand and gears\.gear\.hand are both 'left': the gears of an external "
     r"helical pair have opposite hands"),
    (dict(replace=[('teeth = 26\nmodule = "4 mm"\npressure_angle = "20 deg"',
                    'teeth = 26\nmodule = "4 mm"\npressure_angle = "20 deg"\n'
                    'helix_angle = "10 deg"')]),
     r"gears\.pinion: a helical gear \(helix_angle 10 deg\) needs its hand"),
    (dict(replace=[('gears = ["pinion", "gear"]', 'gears = ["pinion", "pinion"]')]),
     r"meshes\.mesh: gears pinion and pinion are both on shaft pinion_shaft; a mesh joins "
     r"gears of two shafts"),
    (dict(replace=[('[gears.gear]\nshaft = "gear_shaft"\nposition = "80 mm"',
                    '[gears.gear]\nshaft = "gear_shaft"\nposition = "90 mm"')]),
     r"meshes\.mesh: the face centres of gears pinion and gear lie at global z = 80 and 90 mm"),
])
def test_bad_case_files_name_the_field(tmp_path, edit, match):
    with pytest.raises(CaseError, match=match) as err:
        load_case(write(tmp_path, **edit))
    message = str(err.value)
    assert "\n" not in message and message.startswith(str(tmp_path))


def test_gear_graph_loops_and_separate_trains():
    """A mesh that closes a loop, a shaft no mesh reaches: refused, naming them."""
    data = load_case("two_stage_reducer").data()
    data["gears"]["extra"] = {**data["gears"]["pinion2"], "shaft": "input", "face_width": 0.02}
    data["meshes"]["loop"] = {"gears": ["extra", "wheel2"], "centre_distance": 0.4}
    with pytest.raises(CaseError, match=r"the meshes form a closed loop through shafts .* a "
                                        r"planetary stage .* the gear graph must be a tree"):
        parse_case(data, "loop.toml")
    data = load_case("two_stage_reducer").data()
    del data["meshes"]["stage2"], data["gears"]["pinion2"], data["gears"]["wheel2"]
    with pytest.raises(CaseError, match=r"apart.toml: shaft output not joined to the input "
                                        r"shaft input by meshes: two separate trains"):
        parse_case(data, "apart.toml")


def test_override_errors_name_the_override():
    with pytest.raises(CaseError, match=r"unknown field drive\.sped; did you mean drive\.speed"):
        load_case(SPUR, {"drive.sped": 1.0})
    with pytest.raises(CaseError, match=r"'bearings\.model\.x' is not bearings\.<name>\.<field>"
                                        r"|bearings\.model\.x"):
        load_case(SPUR, {"bearings.model.x": 1.0})
    with pytest.raises(CaseError, match=r"gears\.pinion\.speed: the speed is set once"):
        load_case(SPUR, {"gears.pinion.speed": "100 rad/s"})


def test_legacy_file_errors_name_the_old_keys(tmp_path):
    bad = OLD_SPUR.replace('clearance = ["150 um"', 'clearance = ["150 N"')
    with pytest.raises(CaseError, match=r"bearings\.clearance\[1\]: '150 N' is a force"):
        load_case(old_file(tmp_path, bad))
    bad = OLD_SPUR.replace("poisson_ratio = 0.3", "poisson_ration = 0.3")
    with pytest.raises(CaseError, match=r"unknown field shafts\.poisson_ration of the "
                                        r"single-stage schema; did you mean shafts\.poisson_ratio"):
        load_case(old_file(tmp_path, bad))


def test_legacy_warning_is_one_line_naming_the_upgrade(tmp_path):
    path = old_file(tmp_path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        load_case(path)
    (w,) = [w for w in caught if issubclass(w.category, LegacyCaseWarning)]
    text = str(w.message)
    assert "\n" not in text and f"gsb case --upgrade {path}" in text
    assert "docs/case-files.md" in text


def test_gsb_case_upgrade_writes_the_current_schema(tmp_path, capsys):
    from orchestrator.cli import main

    assert main(["case", "--upgrade", str(old_file(tmp_path))]) == 0
    text = capsys.readouterr().out
    assert "[gears.pinion]" in text and "[bearings.4]" in text and "[gear_pair]" not in text
    upgraded = tmp_path / "upgraded.toml"
    upgraded.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error", LegacyCaseWarning)
        assert load_case(upgraded).values == load_case(SPUR).values


def test_cli_prints_a_bad_case_in_one_line(tmp_path, capsys):
    from orchestrator.cli import main

    path = write(tmp_path, replace=[('centre_distance = "366 mm"', 'centre_distance = "1 m"')])
    assert main(["modal", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "gsb modal: error:" in err and "meshes.mesh" in err


def test_schema_table_lists_every_field():
    table = schema_markdown()
    assert all(f"`{f.key}`" in table for f in FIELDS)


def test_case_docs_are_generated_from_the_schema():
    from fmu_src.case import document

    doc = ROOT / "docs" / "case-files.md"
    assert doc.read_text() == document(), "run: python -m fmu_src.case > docs/case-files.md"


def test_shipped_cases_load_by_name_from_any_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert set(shipped_cases()) >= {"baguet2010_spur", "baguet2010_helical",
                                    "two_stage_reducer", "overhung_pinion"}
    assert load_case("baguet2010_spur")["case.name"] == "baguet2010_spur"
    helical = load_case("baguet2010_helical.toml")
    assert helical["gears.pinion.helix_angle"] == pytest.approx(math.radians(12.5))
    assert (helical["gears.pinion.hand"], helical["gears.gear.hand"]) == ("left", "right")
    with pytest.raises(CaseError, match="shipped cases: baguet2010_helical, baguet2010_spur"):
        load_case("baguet2010_nope")
