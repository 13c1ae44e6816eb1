"""Probe of tests/fmu_src/test_exit_hosts.py: a Python process that runs an FMU through a C
library (tests/fmu_src/hosts/exit_host.c, loaded with ctypes) and ends without terminating
it, as a script of OMSimulator's Python API ending without terminate()/delete() does.

``python -m tests.probes.exit_host <library> <unzipped FMU> <model identifier> <guid> <steps>
<how>``: the library instantiates and initialises the FMU and takes the steps; then this
script returns, Python finalises its interpreter, and only afterwards the library's atexit()
handler (``how`` 0) or destructor (``how`` 1) calls fmi2Terminate and fmi2FreeInstance. Prints
``{"started": <exit_host_start's result>}``; the library prints what it does at exit.
"""

from __future__ import annotations

import ctypes
import json
import sys


def main(argv=None) -> int:
    library, folder, model, guid, steps, how = sys.argv[1:] if argv is None else argv
    lib = ctypes.CDLL(library)
    lib.exit_host_start.argtypes = [ctypes.c_char_p] * 3 + [ctypes.c_int] * 2
    lib.exit_host_start.restype = ctypes.c_int
    started = lib.exit_host_start(folder.encode(), model.encode(), guid.encode(), int(steps),
                                  int(how))
    print(json.dumps({"started": started}), flush=True)
    return started


if __name__ == "__main__":
    sys.exit(main())
