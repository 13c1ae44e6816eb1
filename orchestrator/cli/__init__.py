"""The ``gsb`` command line."""

from __future__ import annotations

import argparse
import os
import sys

from bearing_fmu.base import BearingError
from fmu_src.case import CaseError
from gear_fmu.mesh.geometry import GearGeometryError
from orchestrator.cli.options import UsageError
from orchestrator.run.progress import RunInterrupted, startup_log
from orchestrator.run.spec import RunError


def _version() -> str:
    """The installed distribution's version (pyproject.toml), or what is missing."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("gear-shaft-bearing")
    except PackageNotFoundError:
        return "(not installed: pip install -e . gives the version)"


def make_parser() -> argparse.ArgumentParser:
    from orchestrator.cli import bearing, doctor, fmus, modal, plot, reproduce, run, sweep

    parser = argparse.ArgumentParser(
        prog="gsb",
        description="Gear-shaft-bearing nonlinear dynamics (Baguet & Jacquenot 2010).",
    )
    parser.add_argument("--version", action="version", version=f"gsb {_version()}")
    sub = parser.add_subparsers(dest="command", required=True)
    for command_group in (bearing, run, reproduce, fmus, modal, sweep, plot, doctor):
        command_group.add_parser(sub)
    return parser


def _show_warnings(command: str):
    """A ``warnings.showwarning`` that prints a warning of this package (what a run says once,
    such as threads it cannot use) as one line ``gsb <command>: warning: <message>`` on
    stderr; other warnings as Python prints them."""
    import warnings
    from pathlib import Path

    packages = [Path(sys.modules[name].__file__).resolve().parent
                for name in ("bearing_fmu", "gear_fmu", "fmu_src", "orchestrator")]
    default = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        try:
            path = Path(filename).resolve()
            ours = any(path.is_relative_to(p) for p in packages)
        except (OSError, ValueError):
            ours = False
        if not ours:
            return default(message, category, filename, lineno, file, line)
        print(f"gsb {command}: warning: {message}", file=sys.stderr if file is None else file)
    return show


def main(argv: list[str] | None = None) -> int:
    import warnings

    args = make_parser().parse_args(argv)
    try:  # what a first run builds or compiles, printed unless --quiet
        with warnings.catch_warnings(), startup_log(not getattr(args, "quiet", False),
                                                    always=True):
            warnings.showwarning = _show_warnings(args.command)
            return args.func(args)
    except RunInterrupted as exc:
        print(f"gsb {args.command}: {exc}", file=sys.stderr)
        return exc.exit_code
    except (BearingError, CaseError, GearGeometryError, RunError, UsageError) as exc:
        print(f"gsb {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"gsb {args.command}: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # a bug, not the user's input: one line, the traceback on demand
        if os.environ.get("GSB_TRACEBACK"):
            raise
        print(f"gsb {args.command}: internal error: {type(exc).__name__}: {exc} (please "
              "report it; GSB_TRACEBACK=1 shows the traceback)", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
