"""The API reference (docs/api, Sphinx autodoc + numpydoc) builds with warnings as errors.

Same build as ``sphinx-build -W --keep-going -b html docs/api build/docs`` from the repository
root, into a temporary folder. Unresolved cross-references into the four packages are errors
too (``nitpicky`` in docs/api/conf.py).
"""

import importlib.util
import pkgutil
import subprocess
import sys

import pytest

from tests.helpers import ROOT

if importlib.util.find_spec("sphinx") is None:
    pytest.skip("sphinx is not installed (pip install -e '.[docs]')", allow_module_level=True)

PACKAGES = ("bearing_fmu", "gear_fmu", "fmu_src", "orchestrator")

# a few key objects: (page, anchor id)
KEY_OBJECTS = [
    ("bearing_fmu.html", "bearing_fmu.hybrid.model.HybridBearing"),
    ("bearing_fmu.html", "bearing_fmu.affine.AffineLaws"),
    ("bearing_fmu.html", "bearing_fmu.base.BearingModel"),
    ("gear_fmu.html", "gear_fmu.structure.Structure"),
    ("fmu_src.html", "fmu_src.case.FIELDS"),
    ("orchestrator.html", "orchestrator.coupling.master.Master"),
]


def public_modules() -> list[str]:
    """Every module and subpackage of the four packages whose name has no leading underscore."""
    names = list(PACKAGES)
    for package in PACKAGES:
        path = [str(ROOT / package)]
        for info in pkgutil.walk_packages(path, prefix=package + "."):
            if not any(part.startswith("_") for part in info.name.split(".")):
                names.append(info.name)
    return sorted(names)


@pytest.fixture(scope="module")
def html(tmp_path_factory):
    out = tmp_path_factory.mktemp("api-docs")
    cmd = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
           "docs/api", str(out)]
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, f"sphinx-build failed:\n{proc.stdout}\n{proc.stderr}"
    return {page.name: page.read_text(encoding="utf-8") for page in out.glob("*.html")}


@pytest.mark.parametrize(("page", "anchor"), KEY_OBJECTS)
def test_key_objects_are_documented(html, page, anchor):
    assert f'id="{anchor}"' in html[page]


def test_every_public_module_is_documented(html):
    text = "".join(html.values())
    modules = public_modules()
    assert len(modules) > 50
    missing = [m for m in modules if f'id="module-{m}"' not in text]
    assert not missing, f"public modules missing from docs/api: {missing}"
