"""docs/equations.md maps every equation of the paper to code that exists."""

import importlib
import re

from tests.helpers import ROOT

DOC = (ROOT / "docs" / "equations.md").read_text()
TARGET = re.compile(r"`((?:bearing_fmu|gear_fmu|fmu_src|orchestrator)[\w.]*)(?::([\w.]+))?`")


def test_every_target_named_in_the_map_exists():
    targets = TARGET.findall(DOC)
    assert len(targets) > 30
    for module, attr in targets:
        obj = importlib.import_module(module)
        for part in filter(None, attr.split(".")):
            obj = getattr(obj, part)  # AttributeError names the missing target


def test_every_equation_of_the_paper_is_mapped():
    rows = re.findall(r"^\| (\d+) \|", DOC, re.M)
    assert [int(r) for r in rows] == list(range(1, 21))


EQ = re.compile(r"Eqs?\.\s*((?:\(?\d+\)?(?:\s*(?:-|–|,|and|to)\s*)?)+)")


def cited(text: str) -> set[int]:
    """Equation numbers cited in a text: 'Eq. (3)', 'Eq. 2-5', 'Eq. (12)-(16)',
    'Eq. 12, 14, 16'."""
    out = set()
    for span in EQ.findall(text or ""):
        for a, b in re.findall(r"(\d+)\)?(?:\s*(?:-|–|to)\s*\(?(\d+))?", span):
            out.update(range(int(a), int(b or a) + 1))
    return out


def test_each_home_cites_its_equation():
    """The docstring of each home (or of its module) cites the equation it implements."""
    missing = []
    for row in re.findall(r"^\| (\d+) \|[^|]*\|(.*)\|$", DOC, re.M):
        n, homes = int(row[0]), row[1]
        for module, attr in TARGET.findall(homes):
            mod = importlib.import_module(module)
            obj = mod
            for part in filter(None, attr.split(".")):
                obj = getattr(obj, part)
            if n not in cited(obj.__doc__) | cited(mod.__doc__):
                missing.append(f"Eq. {n}: {module}:{attr}")
    assert not missing, "docstrings that do not cite their equation: " + "; ".join(missing)
