"""Probes run by their path (``python tests/probes/standalone/<name>.py``), not with ``-m``:
for an interpreter that must not find this repository, or that must see the package as a user
installed it. Python puts a script's folder first on the path, so this folder holds nothing
else (in tests/probes, ``gear_fmu.py`` would shadow the package)."""
