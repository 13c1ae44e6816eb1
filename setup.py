"""The package list, which pyproject.toml cannot state: the code packages are found, and the
folder ``models/`` (the shipped cases) is installed as the package ``gsb_models``, a name of its
own because a top-level ``models`` would shadow, or be shadowed by, a user's module."""

from setuptools import find_packages, setup

setup(
    packages=[*find_packages(include=["bearing_fmu*", "gear_fmu*", "orchestrator*", "fmu_src*"]),
              "gsb_models"],
    package_dir={"gsb_models": "models"},
)
