"""Case files: the paper's case loads in SI; bad files fail early, naming the field."""

import math

import pytest

from fmu_src.case import FIELDS, CaseError, load_case, schema_markdown, shipped_cases
from tests.helpers import ROOT

SPUR = shipped_cases()["baguet2010_spur"]


def test_paper_spur_case_in_si_units():
    c = load_case(SPUR)
    assert c["gear_pair.module"] == pytest.approx(4e-3)
    assert c["gear_pair.pressure_angle"] == pytest.approx(math.radians(20.0))
    assert c["bearings.clearance"] == pytest.approx([150e-6, 150e-6, 110e-6, 110e-6])
    assert c["shafts.young_modulus"] == pytest.approx(210e9)
    assert c["operation.unbalance"] == pytest.approx([0.6e-3, 0.6e-3])
    assert c["simulation.mesh_periods"] == 2048


def write(tmp_path, text, drop=None, replace=None):
    src = SPUR.read_text()
    if drop:
        src = "\n".join(line for line in src.splitlines() if not line.startswith(drop))
    if replace:
        src = src.replace(*replace)
    p = tmp_path / "case.toml"
    p.write_text(src + text)
    return p


@pytest.mark.parametrize("edit,match", [
    (dict(drop="module ="), r"missing field gear_pair\.module"),
    (dict(replace=('clearance = ["150 um"', 'clearance = ["150 N"')),
     r"bearings\.clearance\[0\]: '150 N' is a force, expected a length"),
    (dict(replace=('"325 rad/s"', '"325 furlongs"')), r"operation\.speed: unknown unit"),
    (dict(replace=('model = "hybrid"', 'model = "magic"')), r"bearings\.model: 'magic' is not"),
    (dict(replace=("poisson_ratio = 0.3", "poisson_ration = 0.3")),
     r"unknown field shafts\.poisson_ration"),
    (dict(replace=("elements = 8", "elements = 7")), r"shafts\.elements = 7 must be even"),
    (dict(replace=('inner_diameter = ["30 mm", "30 mm"]', 'inner_diameter = ["80 mm", "30 mm"]')),
     r"inner_diameter\[0\].*smaller than"),
    (dict(replace=("tolerance = 1e-5", "tolerance = -1")), r"simulation\.tolerance = -1"),
    (dict(replace=("teeth = [26, 157]", "teeth = [26]")), r"gear_pair\.teeth: expected 2"),
])
def test_bad_case_files_name_the_field(tmp_path, edit, match):
    with pytest.raises(CaseError, match=match):
        load_case(write(tmp_path, "", **edit))


def test_unknown_section(tmp_path):
    with pytest.raises(CaseError, match=r"unknown section \[bearing\]"):
        load_case(write(tmp_path, "\n[bearing]\nmodel = 'short'\n"))


def test_overrides_replace_fields_without_editing_the_file():
    c = load_case(SPUR, {"bearings.model": "linear", "simulation.mesh_periods": 4})
    assert c["bearings.model"] == "linear" and c["simulation.mesh_periods"] == 4
    c2 = load_case(SPUR).with_overrides({"operation.speed": "1000 rpm"})
    assert c2["operation.speed"] == pytest.approx(1000 * 2 * math.pi / 60)


def test_schema_table_lists_every_field():
    table = schema_markdown()
    assert all(f"`{f.key}`" in table for f in FIELDS)


def test_case_docs_are_generated_from_the_schema():
    from fmu_src.case import document

    doc = ROOT / "docs" / "case-files.md"
    assert doc.read_text() == document(), "run: python -m fmu_src.case > docs/case-files.md"


def test_shipped_cases_load_by_name_from_any_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert set(shipped_cases()) >= {"baguet2010_spur", "baguet2010_helical"}
    assert load_case("baguet2010_spur")["case.name"] == "baguet2010_spur"
    assert load_case("baguet2010_helical.toml")["gear_pair.helix_angle"] == pytest.approx(
        math.radians(12.5))
    with pytest.raises(CaseError, match="shipped cases: baguet2010_helical, baguet2010_spur"):
        load_case("baguet2010_nope")


def test_model_options_come_from_the_registered_models():
    """bearings.<option> fields exist for every option a registered model declares, and the
    chosen model's own bounds apply (hybrid needs at least 16 nodes, fd 8)."""
    from bearing_fmu import MODELS, model_class

    keys = {f.key for f in FIELDS}
    for name in MODELS:
        for opt in model_class(name).options:
            assert f"bearings.{opt.key}" in keys
    assert load_case(SPUR, {"bearings.model": "fd", "bearings.nodes": 8})["bearings.nodes"] == 8
    with pytest.raises(CaseError, match=r"bearings\.nodes = 8: the hybrid model needs >= 16"):
        load_case(SPUR, {"bearings.nodes": 8})
