"""The package list, which pyproject.toml cannot state: the code packages are found, and the
folder ``models/`` (the shipped cases) is installed as the package ``gsb_models``, a name of its
own because a top-level ``models`` would shadow, or be shadowed by, a user's module."""

from setuptools import find_namespace_packages, find_packages, setup

setup(
    # the native layer's folders (sources, patches, the loader: package data) are packages
    # too, or setuptools warns that it ignores them at every install
    packages=[*find_packages(include=["bearing_fmu*", "gear_fmu*", "orchestrator*", "fmu_src*"]),
              *find_namespace_packages(include=["fmu_src.native*"]), "gsb_models"],
    package_dir={"gsb_models": "models"},
)
