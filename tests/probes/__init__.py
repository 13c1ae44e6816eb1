"""Code the tests run in a fresh interpreter or in their own process, as importable modules.

``python -m tests.probes.<module> <probe> [<JSON keyword arguments>]`` runs one probe
(:func:`tests.helpers.run_isolated` with ``module=``, the repository on the path), and
:func:`tests.helpers.run_here` with ``module=`` calls the same ``main`` in the test's process.
Each module holds the probes of one test module; a probe returns what the test reads, printed
as one JSON line by :func:`dispatch`. No tests here.
"""

from __future__ import annotations

import contextlib
import json
import sys
from collections.abc import Callable


def dispatch(probes: dict[str, Callable[..., object]], argv: list[str] | None = None) -> None:
    """Run the probe named ``argv[0]`` with the keyword arguments of ``argv[1]`` (a JSON
    object; none if absent) and print its result as one JSON line."""
    argv = sys.argv[1:] if argv is None else list(argv)
    if not argv or argv[0] not in probes:
        raise SystemExit(f"usage: <probe> [<JSON keyword arguments>], probe one of "
                         f"{', '.join(probes)}; got {argv!r}")
    kwargs = json.loads(argv[1]) if len(argv) > 1 else {}
    print(json.dumps(probes[argv[0]](**kwargs)))


def probes_of(*functions: Callable[..., object]) -> dict[str, Callable[..., object]]:
    """The probes of a module, by name."""
    return {f.__name__: f for f in functions}


@contextlib.contextmanager
def counted_calls(cls: type, names: tuple[str, ...]):
    """The calls of the methods ``names`` of ``cls`` counted while the block runs (a slave's,
    to tell which FMI calls reached its Python): yields ``{name: count}``, which the caller
    may reset; the methods are restored after the block."""
    calls = dict.fromkeys(names, 0)
    originals = {name: cls.__dict__[name] for name in names}

    def counted(name):
        def call(self, *args):
            calls[name] += 1
            return originals[name](self, *args)
        return call

    for name in names:
        setattr(cls, name, counted(name))
    try:
        yield calls
    finally:
        for name, method in originals.items():
            setattr(cls, name, method)
