"""Sphinx configuration of the API reference (autodoc + numpydoc).

Build from the repository root, warnings as errors::

    sphinx-build -W --keep-going -b html docs/api build/docs
"""

import sys
from pathlib import Path

# the packages from this checkout, installed or not
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

project = "gear-shaft-bearing"
author = "gear-shaft-bearing contributors"
copyright = "2026, gear-shaft-bearing contributors"

extensions = [
    "sphinx.ext.autodoc",
    "numpydoc",
]

html_theme = "alabaster"
html_static_path: list[str] = []
exclude_patterns = ["_build"]
toc_object_entries = False  # the tables of contents list modules, not every object

# numpydoc: no autosummary tables of class members (autodoc documents them once)
numpydoc_show_class_members = False
numpydoc_show_inherited_class_members = False
numpydoc_class_members_toctree = False

# Every public class and function is documented once, in the module that defines it:
# ``ignore-module-all`` skips the names a module only re-exports (listed in its ``__all__``)
# and keeps public helpers that ``__all__`` leaves out but the docstrings refer to.
autodoc_default_options = {
    "members": True,
    "ignore-module-all": True,
    "show-inheritance": True,
    "member-order": "bysource",
}

# Cross-references must resolve (-W turns a broken one into an error). Without network access
# there is no intersphinx, so targets outside the four packages are not checked, nor are the
# private modules (``bearing_fmu.fd._grid``, ...) that the reference leaves out.
nitpicky = True
nitpick_ignore_regex = [
    (r"py:.*", r"(numpy|np|xarray|enum|pathlib|abc|collections|ctypes|typing|zipfile|pythonfmu|fmpy"
               r"|scipy|matplotlib|h5py|dask|argparse|numba)\..*"),
    (r"py:mod", r"(bearing_fmu|gear_fmu|fmu_src|orchestrator)(\.\w+)*\._\w+"),
]
# an annotation inherited from pythonfmu's slave base class, unqualified under Sphinx 7
nitpick_ignore = [("py:class", "DefaultExperiment")]


def setup(app):
    """numpydoc (1.6 to 1.11) makes a jinja environment, and compiles its docstring template in
    it, for every object it documents: a third of this build's time (11 s of 38). One
    environment, made at the first object (its loader the builder's, the same for all), serves
    every object; jinja keeps the compiled template."""
    from numpydoc import docscrape_sphinx

    make = docscrape_sphinx.SandboxedEnvironment
    made = []

    def one_environment(**kwargs):
        if not made:
            made.append(make(**kwargs))
        return made[0]

    docscrape_sphinx.SandboxedEnvironment = one_environment
