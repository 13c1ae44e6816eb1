"""What several commands share: the case argument, the override options and the case they
give (the command line's settings become case fields: the case is their one carrier)."""

from __future__ import annotations

import argparse
import json

__all__ = ["OPTION_FIELDS", "UsageError", "add_case_argument", "add_override_options",
           "case_from_args", "overrides_from_args", "parse_override", "set_overrides"]


class UsageError(ValueError):
    """A command line that cannot be carried out as given; the message names the option and
    its value (``gsb <command>: error: ...``, exit 2)."""


class Override(tuple):
    """A ``--set`` option: the pair (key, value), and the text as typed (``.text``) for the
    messages about it."""

    def __new__(cls, key: str, value, text: str):
        self = super().__new__(cls, (key, value))
        self.text = text
        return self


def parse_override(text: str) -> Override:
    """``section.key=value`` or ``section.name.key=value`` (``*`` for every instance) ->
    (key, value): JSON lists, numbers, else the text ("4 mm")."""
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"--set {text!r}: expected section.key=value or "
                                         "section.name.key=value")
    key, value = (part.strip() for part in text.split("=", 1))
    try:
        return Override(key, json.loads(value), text)
    except ValueError:
        return Override(key, value, text)


def add_case_argument(p, case_help: str = "case file (TOML) or the name of a shipped case, e.g. "
                                 "baguet2010_spur", optional: bool = False) -> None:
    if optional:
        p.add_argument("case", nargs="?", default="baguet2010_spur", help=case_help)
    else:
        p.add_argument("case", help=case_help)
    add_override_options(p)


#: the options that set a case field: option -> the field (``*``: every instance)
OPTION_FIELDS = {"--speed": "drive.speed", "--torque": "drive.torque",
                 "--unbalance": "gears.*.unbalance", "--bearing": "bearings.*.model",
                 "--periods": "simulation.mesh_periods", "--window": "simulation.window"}


def add_override_options(p) -> None:
    p.add_argument("--speed", help="override drive.speed, the input shaft's speed (the others "
                                   "follow from the gear ratios; e.g. '500 rad/s', '3000 rpm')")
    p.add_argument("--torque", help="override drive.torque, the input torque (e.g. '300 N.m')")
    p.add_argument("--unbalance", help="override gears.*.unbalance, the unbalance "
                                       "eccentricity of every gear (e.g. '1.2 mm')")
    p.add_argument("--set", dest="overrides", action="append", type=parse_override, default=[],
                   metavar="SECTION.[NAME.]KEY=VALUE",
                   help="override any case field, NAME an instance or * for every one "
                        "(drive.speed=3000rpm, bearings.3.clearance='120 um', "
                        "bearings.*.model=short; repeatable)")


def set_overrides(pairs) -> dict:
    """The ``--set`` options' (key, value) pairs as case fields, each checked on its own: an
    error names the option as typed (a typo of a key gets the closest field), not the case
    file it would have replaced a field of."""
    from fmu_src.case import CaseError, check_override

    for pair in pairs:
        try:
            check_override(*pair)
        except CaseError as exc:
            typed = getattr(pair, "text", None) or f"{pair[0]}={json.dumps(pair[1])}"
            raise CaseError(f"--set {typed}: {exc}") from None
    return dict(pairs)


def overrides_from_args(args) -> dict:
    """The command line's settings as case fields: the case is their one carrier. Each is
    checked on its own first, the message naming its option (``--speed '3000 rpmx'``)."""
    from fmu_src.case import CaseError, check_override
    from orchestrator.run.spec import check_periods

    overrides = set_overrides(args.overrides)
    periods = getattr(args, "periods", None)
    given = {"--speed": args.speed, "--torque": args.torque, "--unbalance": args.unbalance,
             "--bearing": getattr(args, "bearing", None),
             "--periods": None if periods is None else check_periods(periods),
             "--window": getattr(args, "window", None)}
    for option, value in given.items():
        key = OPTION_FIELDS[option]
        if value is not None:
            try:
                check_override(key, value)
            except CaseError as exc:
                raise CaseError(f"{option} {value!r}: {exc}") from None
            overrides[key] = value
    return overrides


def case_from_args(args):
    """The case file with the command line's overrides applied (checked again)."""
    from fmu_src.case import load_case

    return load_case(args.case, overrides_from_args(args))
