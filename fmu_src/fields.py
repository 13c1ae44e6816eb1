"""What a case field is and how its value is read: the pieces both case schemas share.

A :class:`Field` declares one entry of a case file (its dimension, shape, default and bounds);
:func:`convert` reads a value as written in a file (a number in SI units or ``"value unit"``,
a list for a list field) into SI, and :func:`toml_value` writes it back so that it reloads bit
for bit. The current schema (:mod:`fmu_src.case`) and the single-stage schema of earlier
versions (:mod:`fmu_src.legacy_case`) are two tables of these fields.

Keys are dotted: ``section.field`` for a section that appears once (``drive.speed``),
``section.<instance>.field`` for a section of named instances (``shafts.input.length``,
``bearings.3.clearance``); a schema declares the latter once with ``*`` for the instance
(``shafts.*.length``, :func:`template`).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

from bearing_fmu import MODELS, model_class
from fmu_src.units import UnitError, parse_quantity, symbol

__all__ = ["FREE", "CaseError", "Field", "bound_violation", "convert", "field_spec",
           "instance_names", "option_fields", "template", "toml_value"]

#: the shape of a list field of any length (one value is a list of one)
FREE = "any"


class CaseError(ValueError):
    """A case file that cannot be run; the message names the field."""


@dataclass(frozen=True)
class Field:
    """One entry of a case schema.

    ``kind`` is a dimension of :data:`fmu_src.units.DIMENSIONS`, or ``"count"`` (integer),
    ``"text"``, ``"choice"`` or ``"flag"``. ``shape`` is None for a scalar, the length of a
    list (a scalar is broadcast to it), :data:`FREE` for a list of any length (at least
    ``min_items`` values; a scalar is a list of one), or the name of a sibling list field of
    the same instance whose length it takes (``"length"``: one value per shaft segment, a
    scalar broadcast to every segment).
    """

    key: str
    kind: str
    doc: str
    shape: int | str | None = None
    default: Any = None
    required: bool = True
    minimum: float | None = None
    maximum: float | None = None
    exclusive_minimum: bool = False
    choices: tuple = ()
    min_items: int = 0

    @property
    def name(self) -> str:
        """The field's own name, the last part of its key (``"length"``)."""
        return self.key.rsplit(".", 1)[1]

    @property
    def shape_text(self) -> str:
        """The shape for the documentation: ``1``, ``2``, ``any``, ``1 or more``,
        ``as length``."""
        if self.shape is None:
            return "1"
        if self.shape == FREE:
            return f"{self.min_items} or more" if self.min_items else "any"
        if isinstance(self.shape, int):
            return str(self.shape)
        return f"as {self.shape}"


def field_spec(key, kind, doc, **kw) -> Field:
    """A :class:`Field`; one given a default is optional."""
    if "default" in kw and "required" not in kw:
        kw["required"] = False
    return Field(key, kind, doc, **kw)


def option_fields(prefix: str) -> tuple[Field, ...]:
    """``<prefix><key>`` fields for the options of every registered bearing model
    (:class:`bearing_fmu.base.ModelOption`).

    An option declared by several models (``nodes``: hybrid, fd, linear) is one field; its
    bounds are the widest of the declarations (the chosen model's own bounds are checked after
    loading), its default the constructors' (which must agree).
    """
    merged: dict[str, list] = {}
    for name in MODELS:
        cls = model_class(name)
        defaults = cls.option_defaults()
        for opt in cls.options:
            merged.setdefault(opt.key, []).append((name, opt, defaults[opt.key]))
    out = []
    for key, decl in merged.items():
        _, opt, default = decl[0]
        if any(d != default or o.kind != opt.kind for _, o, d in decl):
            raise RuntimeError(f"bearing option {key!r} is declared with different kinds or "
                               f"defaults by {', '.join(n for n, _, _ in decl)}")
        mins = [o.minimum for _, o, _ in decl]
        maxs = [o.maximum for _, o, _ in decl]
        models = ", ".join(n for n, _, _ in decl)
        out.append(field_spec(f"{prefix}{key}", opt.kind, f"{opt.doc} [models: {models}]",
                              default=default,
                              minimum=None if None in mins else min(mins),
                              maximum=None if None in maxs else max(maxs),
                              exclusive_minimum=all(o.exclusive_minimum for _, o, _ in decl)))
    return tuple(out)


def template(key: str, instance_sections) -> str:
    """The schema key of a case key: the instance replaced by ``*`` in a section of named
    instances (``"shafts.input.length"`` -> ``"shafts.*.length"``), other keys as they are."""
    parts = key.split(".")
    if len(parts) == 3 and parts[0] in instance_sections:
        return f"{parts[0]}.*.{parts[2]}"
    return key


def instance_names(keys, section: str) -> list[str]:
    """The instance names of ``section`` among case keys, in their order
    (``["pinion_shaft", "gear_shaft"]``)."""
    out: dict[str, None] = {}
    for key in keys:
        parts = key.split(".")
        if len(parts) == 3 and parts[0] == section:
            out[parts[1]] = None
    return list(out)


def bound_violation(value, minimum=None, maximum=None, exclusive_minimum=False):
    """The bound ``value`` breaks as ``(relation, limit)`` (``(">", 0.0)``, ``(">=", 5)``,
    ``("<=", 0.7)``), or None: the one check behind case fields, model options and FMU
    variables."""
    if minimum is not None and (value < minimum or (exclusive_minimum and value == minimum)):
        return (">" if exclusive_minimum else ">="), minimum
    if maximum is not None and value > maximum:
        return "<=", maximum
    return None


def _scalar(field: Field, value, name: str):
    kind = field.kind
    if kind == "text":
        if not isinstance(value, str):
            raise CaseError(f"{name}: expected text, got {value!r}")
        return value
    if kind == "choice":
        if value not in field.choices:
            shown = ", ".join(repr(c) if c == "" else c for c in field.choices)
            raise CaseError(f"{name}: {value!r} is not one of {shown}")
        return value
    if kind == "flag":
        if not isinstance(value, bool):
            raise CaseError(f"{name}: expected true or false, got {value!r}")
        return value
    if kind == "count":
        if isinstance(value, bool) or not isinstance(value, int):
            raise CaseError(f"{name}: expected an integer, got {value!r}")
        out = value
    else:
        try:
            out = parse_quantity(value, kind, name)
        except UnitError as exc:
            raise CaseError(str(exc)) from None
    unit = "" if kind == "count" else f" {symbol(kind)}"
    violated = bound_violation(out, field.minimum, field.maximum, field.exclusive_minimum)
    if violated:
        raise CaseError(f"{name} = {value!r}: must be {violated[0]} {violated[1]}{unit}")
    return out


def convert(field: Field, value, key: str, length: int | None = None):
    """A value as written in a case file -> SI (a list for a list field), or
    :class:`CaseError` naming ``key`` (the full key, ``shafts.input.outer_diameter``), the
    value and the limit. ``length``: the number of values of a field whose shape is a
    sibling's (None: not known here, a scalar stays a scalar)."""
    shape = field.shape
    if shape is None:
        if isinstance(value, list):
            raise CaseError(f"{key}: expected one value, got a list")
        return _scalar(field, value, key)
    if shape == FREE:
        items = value if isinstance(value, list) else [value]
        if len(items) < field.min_items:
            raise CaseError(f"{key}: expected at least {field.min_items} value"
                            f"{'s' * (field.min_items > 1)}, got none")
    else:
        n = shape if isinstance(shape, int) else length
        if not isinstance(value, list):
            if n is None:
                return _scalar(field, value, key)
            value = [value] * n
        if n is not None and len(value) != n:
            per = "" if isinstance(shape, int) else f" (one per {shape} value)"
            raise CaseError(f"{key}: expected {n} values{per}, got {len(value)}")
        items = value
    return [_scalar(field, v, f"{key}[{i + 1}]") for i, v in enumerate(items)]


def toml_value(value) -> str:
    """A value of a case in TOML (floats in their shortest round-trip form: the case reloads
    bit for bit)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"cannot write the non-finite value {value!r} to a case file")
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)  # a valid TOML basic string
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {value!r} to a case file")
