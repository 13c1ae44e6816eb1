"""docs/equations.md maps every equation of the paper to code that exists and cites it, and the
code cites no equation the map does not have."""

import importlib
import inspect
import pkgutil
import re

from tests.helpers import ROOT

DOC = (ROOT / "docs" / "equations.md").read_text()
PACKAGES = ("bearing_fmu", "gear_fmu", "fmu_src", "orchestrator")
TARGET = re.compile(r"`((?:bearing_fmu|gear_fmu|fmu_src|orchestrator)[\w.]*)(?::([\w.]+))?`")
#: the map's rows: (equation, homes)
ROWS = [(int(n), homes) for n, homes in re.findall(r"^\| (\d+) \|[^|]*\|(.*)\|$", DOC, re.M)]
#: the equations of Baguet & Jacquenot (2010)
EQUATIONS = list(range(1, 21))


def resolve(module: str, attr: str):
    """(module object, the object ``module:attr`` names); AttributeError names a missing one."""
    mod = importlib.import_module(module)
    obj = mod
    for part in filter(None, attr.split(".")):
        obj = getattr(obj, part)
    return mod, obj


EQ = re.compile(r"Eqs?\.\s*((?:\(?\d+\)?(?:\s*(?:-|–|,|and|to)\s*)?)+)")


def cited(text: str) -> set[int]:
    """Equation numbers cited in a text: 'Eq. (3)', 'Eq. 2-5', 'Eq. (12)-(16)',
    'Eq. 12, 14, 16'."""
    out = set()
    for span in EQ.findall(text or ""):
        for a, b in re.findall(r"(\d+)\)?(?:\s*(?:-|–|to)\s*\(?(\d+))?", span):
            out.update(range(int(a), int(b or a) + 1))
    return out


def test_cited_reads_the_forms_the_code_uses():
    assert cited("Eq. (3) and Eq. 2-5") == {2, 3, 4, 5}
    assert cited("Eqs. (12)-(16); Eq. 12, 14, 16 and 20") == {12, 13, 14, 15, 16, 20}
    assert cited("no equation, the 3rd case") == set()


def test_every_equation_of_the_paper_has_one_row():
    assert [n for n, _ in ROWS] == EQUATIONS


def test_every_row_names_homes_that_exist():
    """Each row names at least one home in the packages, and each imports."""
    empty = [n for n, homes in ROWS if not TARGET.findall(homes)]
    assert not empty, f"rows of docs/equations.md naming no home in the packages: {empty}"
    for module, attr in TARGET.findall(DOC):  # the rows and the paragraph after them
        resolve(module, attr)


def test_each_home_cites_its_equation():
    """The docstring of each home (or of its module, where the module is the equation's) cites
    the equation it implements."""
    missing = []
    for n, homes in ROWS:
        for module, attr in TARGET.findall(homes):
            mod, obj = resolve(module, attr)
            if n not in cited(obj.__doc__) | cited(mod.__doc__):
                missing.append(f"Eq. {n}: {module}:{attr}")
    assert not missing, "docstrings that do not cite their equation: " + "; ".join(missing)


def docstrings():
    """``(where, docstring)`` of every module of the packages and of the classes, functions
    (compiled ones too) and methods each defines."""
    for package in PACKAGES:
        path = importlib.import_module(package).__path__
        names = [package] + [m.name for m in pkgutil.walk_packages(path, package + ".")
                             if not m.name.endswith(".__main__")]  # __main__ runs the CLI
        for name in names:
            mod = importlib.import_module(name)
            yield name, mod.__doc__
            for qual, obj in vars(mod).items():
                if getattr(obj, "__module__", None) != name:
                    continue  # imported from elsewhere
                if inspect.isclass(obj):
                    yield f"{name}:{qual}", obj.__doc__
                    for attr, member in vars(obj).items():
                        function = getattr(member, "__func__", member)  # static, class methods
                        if inspect.isfunction(function) or isinstance(member, property):
                            yield f"{name}:{qual}.{attr}", member.__doc__
                elif inspect.isfunction(obj) or hasattr(obj, "py_func"):
                    yield f"{name}:{qual}", obj.__doc__


def test_the_code_cites_only_equations_the_map_has():
    """A docstring citing an equation number the paper does not have (a typo, a renumbering)
    fails here, naming where."""
    rows = {n for n, _ in ROWS}
    seen, stray = 0, []
    for where, doc in docstrings():
        numbers = cited(doc)
        seen += bool(numbers)
        stray += [f"{where}: Eq. {n}" for n in sorted(numbers - rows)]
    assert seen > 50  # the walk reads the docstrings that cite (about 90)
    assert not stray, "citations of equations not in docs/equations.md: " + "; ".join(stray)
