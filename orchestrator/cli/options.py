"""What several commands share: the case argument, the override options and the case they
give (the command line's settings become case fields: the case is their one carrier)."""

from __future__ import annotations

import argparse

__all__ = ["add_case_argument", "add_override_options", "case_from_args", "overrides_from_args",
           "parse_override"]


def parse_override(text: str):
    """``section.key=value`` -> (key, value): JSON lists, numbers, else the text ("4 mm")."""
    import json

    if "=" not in text:
        raise argparse.ArgumentTypeError(f"--set {text!r}: expected section.key=value")
    key, value = (part.strip() for part in text.split("=", 1))
    try:
        return key, json.loads(value)
    except ValueError:
        return key, value


def add_case_argument(p, case_help: str = "case file (TOML) or the name of a shipped case, e.g. "
                                 "baguet2010_spur", optional: bool = False) -> None:
    if optional:
        p.add_argument("case", nargs="?", default="baguet2010_spur", help=case_help)
    else:
        p.add_argument("case", help=case_help)
    add_override_options(p)


def add_override_options(p) -> None:
    p.add_argument("--speed", help="override operation.speed (e.g. '500 rad/s', '3000 rpm')")
    p.add_argument("--torque", help="override operation.torque (e.g. '300 N.m')")
    p.add_argument("--unbalance", help="override operation.unbalance of both shafts (e.g. "
                                       "'1.2 mm')")
    p.add_argument("--set", dest="overrides", action="append", type=parse_override, default=[],
                   metavar="SECTION.KEY=VALUE", help="override any case field (repeatable)")


def overrides_from_args(args) -> dict:
    """The command line's settings as case fields: the case is their one carrier."""
    from orchestrator.run.spec import check_periods

    overrides = dict(args.overrides)
    periods = getattr(args, "periods", None)
    for key, value in (("operation.speed", args.speed), ("operation.torque", args.torque),
                       ("operation.unbalance", args.unbalance),
                       ("bearings.model", getattr(args, "bearing", None)),
                       ("simulation.mesh_periods",
                        None if periods is None else check_periods(periods))):
        if value is not None:
            overrides[key] = value
    return overrides


def case_from_args(args):
    """The case file with the command line's overrides applied (checked again)."""
    from fmu_src.case import load_case

    return load_case(args.case, overrides_from_args(args))
