"""Probe of tests/system/test_fmu_system.py: an FMU instantiated in a Python where one of the
packages its code needs cannot be imported.

``python -m tests.probes.missing_requirement instantiate '{"fmu": ..., "blocked": "numba"}'``
puts a finder in front of the import system that refuses ``blocked`` (ImportError, as for a
package that is not installed) before anything else is imported, then instantiates the FMU
through the FMI C API with ctypes and the standard library only (fmpy needs numpy, which may
be the package refused). Returns whether fmi2Instantiate returned NULL and every message the
FMU gave the host's logger callback.
"""

from __future__ import annotations

import sys


class Refuse:
    """A meta-path finder that refuses one top-level package and its submodules."""

    def __init__(self, name: str):
        self.name = name

    def find_spec(self, fullname, path=None, target=None):
        if fullname == self.name or fullname.startswith(self.name + "."):
            raise ImportError(f"No module named {fullname!r} (refused by the test)",
                              name=fullname)
        return None


def instantiate(fmu: str, blocked: str) -> dict:
    """fmi2Instantiate of ``fmu`` (co-simulation, logging on) with ``blocked`` refused."""
    import ctypes
    import tempfile
    import zipfile
    from pathlib import Path
    from xml.etree import ElementTree as ET

    sys.meta_path.insert(0, Refuse(blocked))
    folder = Path(tempfile.mkdtemp(prefix="gsb_refused_"))
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    md = ET.parse(folder / "modelDescription.xml").getroot()
    identifier = md.find("CoSimulation").get("modelIdentifier")
    lib = ctypes.CDLL(str(folder / "binaries" / "linux64" / f"{identifier}.so"))

    messages = []
    logger_type = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int,
                                   ctypes.c_char_p, ctypes.c_char_p)

    def logger(env, name, status, category, message):
        messages.append([status, (message or b"").decode(errors="replace")])

    libc = ctypes.CDLL(None)
    libc.calloc.restype = ctypes.c_void_p
    libc.calloc.argtypes = [ctypes.c_size_t, ctypes.c_size_t]
    libc.free.argtypes = [ctypes.c_void_p]
    calloc_type = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_size_t, ctypes.c_size_t)
    free_type = ctypes.CFUNCTYPE(None, ctypes.c_void_p)

    class Callbacks(ctypes.Structure):
        _fields_ = (("logger", logger_type), ("allocateMemory", calloc_type),
                    ("freeMemory", free_type), ("stepFinished", ctypes.c_void_p),
                    ("componentEnvironment", ctypes.c_void_p))

    keep = (logger_type(logger), calloc_type(lambda n, size: libc.calloc(n, size)),
            free_type(lambda p: libc.free(p)))
    callbacks = Callbacks(keep[0], keep[1], keep[2], None, None)
    lib.fmi2Instantiate.restype = ctypes.c_void_p
    lib.fmi2Instantiate.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                                    ctypes.c_char_p, ctypes.c_void_p, ctypes.c_int,
                                    ctypes.c_int]
    component = lib.fmi2Instantiate(b"x", 1, md.get("guid").encode(),
                                    (folder / "resources").as_uri().encode(),
                                    ctypes.addressof(callbacks), 0, 1)
    if component:
        lib.fmi2FreeInstance.argtypes = [ctypes.c_void_p]
        lib.fmi2FreeInstance(component)
    return {"null": not component, "messages": messages, "executable": sys.executable,
            "imported": blocked in sys.modules}


def main(argv: list[str] | None = None) -> None:
    from tests.probes import dispatch, probes_of

    dispatch(probes_of(instantiate), argv)


if __name__ == "__main__":
    main()
