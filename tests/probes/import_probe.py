"""Which ``.toml`` files importing some modules opens, in a fresh interpreter.

``python -m tests.probes.import_probe MODULE ... [--call MODULE:FUNCTION]`` imports the
modules, then calls the function (a control: it should read a file), and prints one JSON
object on its last
line: ``{"on_import": [paths], "on_call": [paths]}``, the ``.toml`` files opened during each
phase. The paths are seen by an audit hook on the ``open`` event, which ``builtins.open``,
``io.open_code``, ``pathlib.Path.read_text`` and ``tomllib.load`` of a file all raise
(:func:`sys.addaudithook`), so no way of reading a case file escapes it.
"""

from __future__ import annotations

import importlib
import json
import os
import sys


def main(argv: list[str]) -> dict:
    call = None
    if "--call" in argv:
        at = argv.index("--call")
        call, argv = argv[at + 1], argv[:at] + argv[at + 2:]
    opened: dict[str, list[str]] = {"on_import": [], "on_call": []}
    phase = ["on_import"]

    def hook(event: str, args: tuple) -> None:
        if event == "open" and args and isinstance(args[0], (str, bytes, os.PathLike)):
            path = os.fsdecode(args[0])
            if path.endswith(".toml"):
                opened[phase[0]].append(path)

    sys.addaudithook(hook)
    for name in argv:
        importlib.import_module(name)
    if call is not None:
        phase[0] = "on_call"
        module, function = call.split(":")
        getattr(importlib.import_module(module), function)()
    return opened


if __name__ == "__main__":
    print(json.dumps(main(sys.argv[1:])))
