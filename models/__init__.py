"""The shipped case files (TOML), installed as the package ``gsb_models``.

They are data: :func:`fmu_src.case.shipped_cases` finds them with :mod:`importlib.resources`,
so a run finds them from any folder, an installed package and an FMU's staged code alike.
Schema: ``docs/case-files.md``.
"""
