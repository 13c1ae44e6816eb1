"""The FMI variable contracts of the FMUs and their wiring (one source of truth).

:func:`bearing_variables`: every bearing FMU (one per model of :data:`bearing_fmu.MODELS`)
exposes exactly these variables, so a system swaps one for another by file name alone. The FMU
works in the GLOBAL frame (s, t) of the gear system; its parameters ``frame_angle`` and
``rotation_sign`` place the bearing's local frame (:class:`bearing_fmu.frames.LocalFrame`) in
which the film model runs. Besides the force and its stiffness and damping (Eq. 18) it outputs
the journal state they were evaluated at (its inputs, ``s_eval`` ...): what the gear-shaft FMU
linearises about (Eq. 17).

:func:`gear_variables`: the gear-shaft FMU (``GearShaft``) of a case's gear train: the
structural fields of its case as parameters (:func:`gear_case_fields`); one group of ports per
bearing, named after it (bearing ``b``: the bearing FMU's outputs as inputs ``F_s_b``,
``K_ss_b``, ..., ``s_eval_b``, ...; its journal state ``s_b`` ... ``t_dot_b`` and its shaft's
speed ``omega_b`` as outputs; ``support_load_s_b``, ``rotation_sign_b`` ... as calculated
parameters); per mesh ``m`` the outputs ``mesh_force_m`` and ``transmission_error_m``; per gear
``g`` the outputs ``u_g`` and ``v_g`` (:func:`step_output_names`). Every list of names follows
the train's layout (:func:`fmu_src.description.layout`): nothing here counts bearings, meshes
or gears. The paper's bearings are named ``1`` ... ``4``, so its ports are ``F_s_1`` ... A
system is wired by plain output -> input connections (:func:`connections`), with no arithmetic
in between.

Every bound a value must respect is declared here (:class:`FmiVar`: minimum, maximum, choices;
written as ``min``/``max`` into modelDescription.xml) and checked by the FMUs when the value is
set (:meth:`FmiVar.check`). The layouts of the law inputs (14 per bearing) and of the journal
outputs (4 per bearing) are defined once (:func:`law_input_names`, :func:`pack_laws`,
:func:`unpack_law_arrays`, :func:`unpack_journal`). Units are the dimensions of
:mod:`fmu_src.units`. The tables are rendered into ``docs/fmu-variables.md`` by
:mod:`fmu_src.build.variables_doc` and into each FMU's modelDescription.xml by
:mod:`fmu_src.build.fmus`.

The two variable lists take start values from the shipped case ``baguet2010_spur``; they are
built on first use and kept (:func:`bearing_variables`, :func:`gear_variables`), so importing
this module reads no file.
"""

from __future__ import annotations

import functools
import math
import re
from dataclasses import dataclass

import numpy as np
from numba import njit

from bearing_fmu import MODELS, model_class
from bearing_fmu.affine import AffineLaws
from fmu_src.case import (
    FIELDS,
    INSTANCE_SECTIONS,
    bound_violation,
    model_option_fields,
    shipped_case,
)
from fmu_src.description import bearing_frames, layout, speed_profile
from fmu_src.fields import CaseError, template
from fmu_src.units import symbol
from gear_fmu.layout import Layout

__all__ = ["BEARING_RESOURCE", "GEAR_DEFAULT_CASE", "LAWS_PER_BEARING", "FmiVar",
           "ValueRefused", "bearing_component", "bearing_fmu_name", "bearing_names",
           "bearing_option_keys", "bearing_variables", "case_parameters",
           "check_constant_speed", "connections",
           "fmi_name", "gear_case_fields", "gear_names", "gear_parameters", "gear_variables",
           "journal_output_names", "law_input_names", "mesh_names", "pack_law_arrays",
           "pack_laws", "parameter_field", "speed_output_names", "step_output_names",
           "support_load_names", "transmission_fields", "transmission_output_names",
           "transmission_variables",
           "unpack_journal", "unpack_law_arrays"]


class ValueRefused(ValueError):
    """A value an FMU variable does not accept (the message names it and the limit)."""


@dataclass(frozen=True)
class FmiVar:
    """One FMI 2.0 scalar variable.

    ``dimension`` is a key of :data:`fmu_src.units.DIMENSIONS` ("" for integers, strings and
    flags); ``minimum``/``maximum`` bound it (``exclusive_minimum``: the minimum itself is
    refused); ``choices`` lists the only values allowed.
    """

    name: str
    causality: str  # parameter | calculatedParameter | input | output
    type: str  # Real | Integer | Boolean | String
    dimension: str
    start: float | int | str | bool
    description: str
    minimum: float | None = None
    maximum: float | None = None
    exclusive_minimum: bool = False
    choices: tuple = ()

    @property
    def unit(self) -> str:
        """The unit symbol (:mod:`fmu_src.units`), "" for none."""
        return symbol(self.dimension) if self.dimension else ""

    def check(self, value) -> None:
        """Raise :class:`ValueRefused` (value, unit and limit in the message) for a value this
        variable does not accept: a non-finite number, one out of its bounds or choices."""
        if self.type in ("Real", "Integer") and not math.isfinite(value):
            raise ValueRefused(f"{self.name} = {value!r}{self._unit_text()} refused: not a "
                               "finite number")
        if self.choices and value not in self.choices:
            raise ValueRefused(f"{self.name} = {value!r} refused: must be one of "
                               f"{', '.join(map(str, self.choices))}")
        if self.minimum is None and self.maximum is None:
            return
        violated = bound_violation(value, self.minimum, self.maximum, self.exclusive_minimum)
        if violated:
            unit = self._unit_text()
            raise ValueRefused(f"{self.name} = {value!r}{unit} refused: must be {violated[0]} "
                               f"{violated[1]:g}{unit}")

    def _unit_text(self) -> str:
        """" <unit>" for a message, "" for none or "1"."""
        unit = self.unit
        return f" {unit}" if unit and unit != "1" else ""


_P, _CP, _I, _O = "parameter", "calculatedParameter", "input", "output"
_POS = dict(minimum=0.0, exclusive_minimum=True)

# --- bearing FMUs --------------------------------------------------------------------------


def bearing_fmu_name(model: str) -> str:
    """File stem of the bearing FMU of model ``model`` (``hybrid`` -> ``BearingHybrid``): the
    one place FMU names are made."""
    model_class(model)  # an unknown name is an error here too
    return "Bearing" + model.capitalize()


#: names of the force, stiffness and damping outputs (row-major matrices)
FORCE_NAMES = ("F_s", "F_t")
STIFFNESS_NAMES = ("K_ss", "K_st", "K_ts", "K_tt")
DAMPING_NAMES = ("C_ss", "C_st", "C_ts", "C_tt")
#: the journal-state inputs of a bearing FMU, and the outputs that echo them
STATE_NAMES = ("s", "t", "s_dot", "t_dot")
EVAL_NAMES = ("s_eval", "t_eval", "s_dot_eval", "t_dot_eval")
#: what a bearing FMU gives the gear-shaft FMU (the law of Eq. 17 and where it was evaluated)
BEARING_OUTPUTS = (*FORCE_NAMES, *STIFFNESS_NAMES, *DAMPING_NAMES, *EVAL_NAMES)
#: the gear-shaft FMU's law inputs per bearing (:data:`BEARING_OUTPUTS`)
LAWS_PER_BEARING = len(BEARING_OUTPUTS)


def _paper_bearing():
    """Start values of the bearing data: bearing 1 of the paper's spur case (Table 3)."""
    case = shipped_case("baguet2010_spur")
    first = case.names("bearings")[0]
    return {k: case[f"bearings.{first}.{k}"] for k in ("diameter", "length", "clearance",
                                                       "viscosity")}


def _field_variable(name: str, f, value, causality: str = _P) -> FmiVar:
    """An FMU variable for one value of a case field (:class:`fmu_src.case.Field`)."""
    bounds = dict(minimum=f.minimum, maximum=f.maximum, exclusive_minimum=f.exclusive_minimum)
    if f.kind == "count":
        return FmiVar(name, causality, "Integer", "", int(value), f.doc, **bounds)
    if f.kind == "flag":
        return FmiVar(name, causality, "Boolean", "", bool(value), f.doc)
    if f.kind in ("text", "choice"):
        return FmiVar(name, causality, "String", "", str(value), f.doc, choices=f.choices)
    return FmiVar(name, causality, "Real", f.kind, float(value), f.doc, **bounds)


def _option_variables() -> tuple[FmiVar, ...]:
    """One parameter per option of the registered bearing models (:mod:`fmu_src.case` merges
    them the same way), so every bearing FMU has the same variables."""
    return tuple(_field_variable(f.name, f, f.default) for f in model_option_fields())


@functools.cache
def bearing_variables() -> tuple[FmiVar, ...]:
    """The variables of every bearing FMU (module docstring); the start values of the bearing
    data are the paper's pinion bearing (Table 3), read from the shipped case on first use."""
    b = _paper_bearing()
    return (
        # bearing data (start values: the paper's pinion bearing, Table 3)
        FmiVar("D", _P, "Real", "length", b["diameter"], "bearing diameter D = 2R", **_POS),
        FmiVar("L", _P, "Real", "length", b["length"], "bearing length L", **_POS),
        FmiVar("C", _P, "Real", "length", b["clearance"], "radial clearance C (< D/2)", **_POS),
        FmiVar("mu", _P, "Real", "viscosity", b["viscosity"],
               "dynamic viscosity of the lubricant", **_POS),
        FmiVar("frame_angle", _P, "Real", "angle", 0.0,
               "angle from the global s axis to the bearing's local x axis"),
        FmiVar("rotation_sign", _P, "Integer", "", 1,
               "+1 if the shaft turns about +z, -1 if about -z (local frame mirrored)",
               choices=(1, -1)),
        *_option_variables(),
        # journal state at the bearing node, global frame
        FmiVar("s", _I, "Real", "length", 0.0,
               "journal-centre displacement along s (global frame)"),
        FmiVar("t", _I, "Real", "length", 0.0,
               "journal-centre displacement along t (global frame)"),
        FmiVar("s_dot", _I, "Real", "velocity", 0.0, "journal-centre velocity along s"),
        FmiVar("t_dot", _I, "Real", "velocity", 0.0, "journal-centre velocity along t"),
        FmiVar("omega", _I, "Real", "angular_speed", 325.0, "shaft speed magnitude", **_POS),
        # film force on the journal and its linearisation, global frame
        FmiVar("F_s", _O, "Real", "force", 0.0, "film force on the journal along s"),
        FmiVar("F_t", _O, "Real", "force", 0.0, "film force on the journal along t"),
        FmiVar("K_ss", _O, "Real", "stiffness", 0.0, "stiffness -dF_s/ds"),
        FmiVar("K_st", _O, "Real", "stiffness", 0.0, "stiffness -dF_s/dt"),
        FmiVar("K_ts", _O, "Real", "stiffness", 0.0, "stiffness -dF_t/ds"),
        FmiVar("K_tt", _O, "Real", "stiffness", 0.0, "stiffness -dF_t/dt"),
        FmiVar("C_ss", _O, "Real", "damping", 0.0, "damping -dF_s/ds_dot"),
        FmiVar("C_st", _O, "Real", "damping", 0.0, "damping -dF_s/dt_dot"),
        FmiVar("C_ts", _O, "Real", "damping", 0.0, "damping -dF_t/ds_dot"),
        FmiVar("C_tt", _O, "Real", "damping", 0.0, "damping -dF_t/dt_dot"),
        FmiVar("s_eval", _O, "Real", "length", 0.0,
               "the input s at which F, K and C were evaluated (what a structure "
               "linearises about)"),
        FmiVar("t_eval", _O, "Real", "length", 0.0,
               "the input t at which F, K and C were evaluated"),
        FmiVar("s_dot_eval", _O, "Real", "velocity", 0.0,
               "the input s_dot at which F, K and C were evaluated"),
        FmiVar("t_dot_eval", _O, "Real", "velocity", 0.0,
               "the input t_dot at which F, K and C were evaluated"),
        FmiVar("eccentricity", _O, "Real", "dimensionless", 0.0,
               "eccentricity ratio e/C of the journal"),
        FmiVar("n_solves", _O, "Integer", "", 0,
               "film-force evaluations so far (Reynolds solves for film models)"),
    )


def bearing_option_keys() -> tuple[str, ...]:
    """Names of the bearing FMU parameters that are model options (all registered models)."""
    return tuple(sorted({o.key for name in MODELS for o in model_class(name).options},
                        key=[v.name for v in bearing_variables()].index))


# --- gear-shaft FMU ------------------------------------------------------------------------

#: the case the gear-shaft FMU carries by default (its parameters' start values)
GEAR_DEFAULT_CASE = "baguet2010_spur.toml"
#: start values of the law inputs: isotropic 1e8 N/m, 1e4 N s/m, no force (stand-alone runs)
_LAW_START = {"K_ss": 1e8, "K_tt": 1e8, "C_ss": 1e4, "C_tt": 1e4}
_LAW_DIMENSION = {**dict.fromkeys(FORCE_NAMES, "force"),
                  **dict.fromkeys(STIFFNESS_NAMES, "stiffness"),
                  **dict.fromkeys(DAMPING_NAMES, "damping"),
                  "s_eval": "length", "t_eval": "length", "s_dot_eval": "velocity",
                  "t_dot_eval": "velocity"}
_STATE_TEXT = {
    "s": ("length", "bearing {b}: journal-centre displacement along s (global frame)"),
    "t": ("length", "bearing {b}: journal-centre displacement along t (global frame)"),
    "s_dot": ("velocity", "bearing {b}: journal-centre velocity along s"),
    "t_dot": ("velocity", "bearing {b}: journal-centre velocity along t"),
}


def _train(case) -> Layout:
    """The gear train of a case (a :class:`fmu_src.case.Case` or its
    :class:`gear_fmu.layout.Layout`)."""
    return case if isinstance(case, Layout) else layout(case)


def bearing_names(case) -> tuple[str, ...]:
    """The bearings' names in the layout's order (the case's): the suffix of each bearing's
    group of ports (``"1"`` ... ``"4"`` for the paper's cases)."""
    return _train(case).bearing_names


def mesh_names(case) -> tuple[str, ...]:
    """The meshes' names in the layout's order."""
    return _train(case).mesh_names


def gear_names(case) -> tuple[str, ...]:
    """The gears' names in the layout's order."""
    return tuple(g.name for g in _train(case).gears)


def law_input_names(case) -> list[str]:
    """The gear-shaft FMU's law inputs: bearing-major (the layout's order), the bearing FMU's
    outputs (:data:`BEARING_OUTPUTS`, :data:`LAWS_PER_BEARING` of them) within, suffixed with
    the bearing's name (``F_s_1``, ..., ``t_dot_eval_4`` for the paper's case)."""
    return [f"{n}_{b}" for b in bearing_names(case) for n in BEARING_OUTPUTS]


def journal_output_names(case) -> list[str]:
    """The journal outputs: bearing-major, (s, t, s_dot, t_dot) within (journal_states)."""
    return [f"{n}_{b}" for b in bearing_names(case) for n in STATE_NAMES]


def speed_output_names(case) -> list[str]:
    """The speed of each bearing's shaft, ``omega_<bearing>``, in the bearings' order."""
    return [f"omega_{b}" for b in bearing_names(case)]


def support_load_names(case) -> list[str]:
    """The support loads: bearing-major, (s, t) within."""
    return [f"support_load_{a}_{b}" for b in bearing_names(case) for a in ("s", "t")]


def step_output_names(case) -> list[str]:
    """What the structure outputs at each step, in the row of
    :class:`orchestrator.coupling.step.StepBlock`: each mesh's force ``mesh_force_<mesh>``,
    then each mesh's ``transmission_error_<mesh>``, then ``u_<gear>``, ``v_<gear>`` of each
    gear's node (the layout's orders)."""
    lay = _train(case)
    return [*(f"mesh_force_{m}" for m in lay.mesh_names),
            *(f"transmission_error_{m}" for m in lay.mesh_names),
            *(f"{a}_{g.name}" for g in lay.gears for a in ("u", "v"))]


def _step_output_variables(lay: Layout) -> list[FmiVar]:
    """The variables of :func:`step_output_names`."""
    pairs = {m.name: m.gears for m in lay.meshes}
    return [*(FmiVar(f"mesh_force_{m}", _O, "Real", "force", 0.0,
                     f"mesh {m} (gears {pairs[m][0]} and {pairs[m][1]}): total normal tooth "
                     "load (the sum of the slice loads)") for m in lay.mesh_names),
            *(FmiVar(f"transmission_error_{m}", _O, "Real", "length", 0.0,
                     f"mesh {m}: transmission error r_b1 theta_1 + r_b2 theta_2 of its gear "
                     "nodes' elastic torsion") for m in lay.mesh_names),
            *(FmiVar(f"{a}_{g.name}", _O, "Real", "length", 0.0,
                     f"gear {g.name}: node displacement along {axis}")
              for g in lay.gears for a, axis in (("u", "s"), ("v", "t")))]


def _unique(variables, case) -> tuple[FmiVar, ...]:
    """``variables``, or a :class:`~fmu_src.fields.CaseError` naming two that one name would
    denote (a bearing ``a`` has the output ``s_dot_a``, which is also ``s`` of a bearing
    ``dot_a``)."""
    seen: set = set()
    for v in variables:
        if v.name in seen:
            source = getattr(case, "source", None) or "the case"
            raise CaseError(f"{source}: two FMU variables would be named {v.name!r}: rename "
                            "the bearing, mesh or gear whose name makes it (a name is the "
                            "suffix of its ports, e.g. s_<bearing>, mesh_force_<mesh>)")
        seen.add(v.name)
    return tuple(variables)


def pack_laws(laws: AffineLaws, out: np.ndarray) -> None:
    """Write the affine laws of every bearing (Eq. 17, global frame) into ``out``, the law
    inputs in the order of :func:`law_input_names` (:data:`LAWS_PER_BEARING` per bearing):
    each law's expansion
    (force, Kb, Cb and the journal state it was linearised about;
    :meth:`bearing_fmu.affine.AffineLaws.expansion`)."""
    states, force, kb, cb = laws.expansion()
    c = np.ascontiguousarray
    pack_law_arrays(c(states, dtype=np.float64), c(force, dtype=np.float64),
                    c(kb, dtype=np.float64), c(cb, dtype=np.float64),
                    out.reshape(len(states), LAWS_PER_BEARING))


@njit(cache=True)
def pack_law_arrays(states, force, kb, cb, out):
    """:func:`pack_laws` on the arrays (states (nb, 4), force (nb, 2), kb, cb (nb, 2, 2)) into
    ``out`` (nb, 14), compiled (a numpy slice per block pays a call each; the master's
    compiled loop through the FMUs calls it too)."""
    for j in range(states.shape[0]):
        for r in range(2):
            out[j, r] = force[j, r]
            for c in range(2):
                out[j, 2 + 2 * r + c] = kb[j, r, c]
                out[j, 6 + 2 * r + c] = cb[j, r, c]
        for i in range(4):
            out[j, 10 + i] = states[j, i]


def unpack_law_arrays(values):
    """``(f0, kb, cb)`` of the affine laws in the law inputs (14 per bearing, order of
    :func:`law_input_names`): Eq. (17) about the states ``s_eval_<bearing>`` ..., with the
    arithmetic of :meth:`bearing_fmu.affine.AffineLaws.linearise` (``F + (Kb X) + (Cb Xdot)``,
    each product summed in order), so the laws are the master's bit for bit. Compiled: the
    gear FMU unpacks at every doStep."""
    return _unpack(np.asarray(values, dtype=np.float64).reshape(-1, LAWS_PER_BEARING))


@njit(cache=True)
def _unpack(v):
    """:func:`unpack_law_arrays` on the (nb, 14) inputs."""
    nb = v.shape[0]
    f0 = np.empty((nb, 2))
    kb = np.empty((nb, 2, 2))
    cb = np.empty((nb, 2, 2))
    for j in range(nb):
        x = v[j, 10]
        y = v[j, 11]
        u = v[j, 12]
        w = v[j, 13]
        for r in range(2):
            k0 = v[j, 2 + 2 * r]
            k1 = v[j, 3 + 2 * r]
            c0 = v[j, 6 + 2 * r]
            c1 = v[j, 7 + 2 * r]
            f0[j, r] = v[j, r] + (k0 * x + k1 * y) + (c0 * u + c1 * w)
            kb[j, r, 0] = k0
            kb[j, r, 1] = k1
            cb[j, r, 0] = c0
            cb[j, r, 1] = c1
    return f0, kb, cb


def unpack_journal(values) -> np.ndarray:
    """(nb, 4) journal states [s, t, s_dot, t_dot] of the bearings from the journal outputs
    (order of :func:`journal_output_names`)."""
    return np.asarray(values, dtype=float).reshape(-1, 4)


def check_constant_speed(case, what: str) -> None:
    """CaseError naming ``what`` (an export) for a case whose input speed is not constant
    (``drive.speed_profile``): what it writes fixes each bearing's speed (an SSP's bearing
    components take ``omega`` as a parameter)."""
    if speed_profile(case).varies:
        raise CaseError(f"{what}: drive.speed_profile = {case['drive.speed_profile']!r}: its "
                        f"bearings would turn at drive.speed throughout; a run-up runs with "
                        f"gsb run (in-process or through the FMUs)")


def gear_case_fields():
    """The case fields (schema templates, :data:`fmu_src.case.FIELDS`) the gear-shaft FMU
    exposes as parameters: the case's name, the shafts, gears, meshes and discs, where each
    bearing sits (its shaft and position), the drive, the damping model, the structure's
    tolerance and time-integration switches (the rest of the bearing fields belong to the
    bearing FMUs, the run length, the coupled iterations and the report's window to the
    master). A run-up's ``drive.speed_profile`` is one of them: the structure follows it, the
    master sets each bearing FMU's input ``omega`` at every step."""
    master_only = ("simulation.steps_per_mesh_period", "simulation.mesh_periods",
                   "simulation.max_iterations", "simulation.window")
    return tuple(f for f in FIELDS if f.key not in master_only and (
                 f.key.split(".")[0] in ("shafts", "gears", "meshes", "discs", "drive")
                 or f.key in ("case.name", "bearings.*.shaft", "bearings.*.position")
                 or f.key.startswith("simulation.")))


def gear_parameters(case) -> list[tuple]:
    """``(FMU parameter name, case field, value)`` of every gear-shaft FMU parameter of a
    case: its keys as FMI names (``drive.torque``, ``gears.pinion.module``,
    ``bearings.'1'.position``: :func:`fmi_name`); a list field one per entry,
    ``shafts.pinion_shaft.outer_diameter[1]``, ``meshes.mesh.gears[2]`` (FMI's 1-based index
    notation; :func:`parameter_field` inverts the name)."""
    return case_parameters(case, gear_case_fields())


def case_parameters(case, fields) -> list[tuple]:
    """``(FMU parameter name, case field, value)`` of every key of ``case`` whose schema field
    is one of ``fields`` (the naming of :func:`gear_parameters`), in the case's order; a
    field left at None (``drive.input_position``: the shaft's start) has no parameter."""
    keys = {f.key: f for f in fields}
    out = []
    for key, value in case.values.items():
        field = keys.get(template(key, INSTANCE_SECTIONS))
        if field is None or value is None:
            continue
        name = fmi_name(key)
        if field.shape is None:
            out.append((name, field, value))
        else:
            out += [(f"{name}[{i + 1}]", field, v) for i, v in enumerate(value)]
    return out


_IDENTIFIER = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def fmi_name(key: str) -> str:
    """A case key as an FMI 2.0 structured name: a part that is no identifier (an instance
    named ``1``) quoted, as the standard's Q-names are (``"bearings.1.clearance"`` ->
    ``"bearings.'1'.clearance"``); :func:`parameter_field` drops the quotes."""
    return ".".join(p if _IDENTIFIER.match(p) else f"'{p}'" for p in key.split("."))


_INDEXED = re.compile(r"^(.*)\[(\d+)\]$")


def parameter_field(name: str) -> tuple[str, int | None]:
    """``(case field key, 0-based index or None)`` of a gear-shaft FMU parameter name
    (:func:`gear_parameters`): ``"meshes.mesh.gears[2]"`` -> ``("meshes.mesh.gears", 1)``,
    ``"bearings.'1'.position"`` -> ``("bearings.1.position", None)`` (case names hold no
    quote)."""
    name = name.replace("'", "")
    m = _INDEXED.match(name)
    return (name, None) if m is None else (m.group(1), int(m.group(2)) - 1)


def gear_variables(case=None) -> tuple[FmiVar, ...]:
    """The gear-shaft FMU's variables for the gear train of ``case`` (module docstring), the
    case parameters starting at its values (default: the shipped :data:`GEAR_DEFAULT_CASE`,
    read on first use and kept: the variables of the gear-shaft FMU built for the shipped
    case). A :class:`~fmu_src.fields.CaseError` for names that would make two variables of one
    name."""
    if case is None:
        return _shipped_gear_variables()
    lay = _train(case)
    names = lay.bearing_names
    frames = bearing_frames(lay)
    params = [_field_variable(n, f, v) for n, f, v in gear_parameters(case)]
    return _unique((
        *params,
        *(FmiVar(f"{n}_{b}", _I, "Real", _LAW_DIMENSION[n], _LAW_START.get(n, 0.0),
                 f"bearing {b}: the bearing FMU's {n} (connect bearing {b}'s output {n})")
          for b in names for n in BEARING_OUTPUTS),
        *(FmiVar(f"{n}_{b}", _O, "Real", _STATE_TEXT[n][0], 0.0, _STATE_TEXT[n][1].format(b=b))
          for b in names for n in STATE_NAMES),
        *(FmiVar(f"omega_{b}", _O, "Real", "angular_speed", 0.0,
                 f"bearing {b}: speed magnitude of its shaft (connect to bearing {b}'s omega)")
          for b in names),
        *_step_output_variables(lay),
        FmiVar("iterations", _O, "Integer", "", 0,
               "Newton/contact iterations (linear solves) of the last step or static solution"),
        *(FmiVar(f"support_load_{a}_{b}", _CP, "Real", "force", 0.0,
                 f"bearing {b}: static load of the structure on the bearing along {a} with "
                 "stiff (1e12 N/m) supports (a first guess of the static solution)")
          for b in names for a in ("s", "t")),
        *(FmiVar(f"rotation_sign_{b}", _CP, "Integer", "", fr.rotation_sign,
                 f"bearing {b}: the rotation_sign its bearing FMU needs (+1: shaft turning "
                 "about +z)") for b, fr in zip(names, frames, strict=True)),
        *(FmiVar(f"frame_angle_{b}", _CP, "Real", "angle", fr.angle,
                 f"bearing {b}: the frame_angle its bearing FMU needs")
          for b, fr in zip(names, frames, strict=True)),
    ), case)


@functools.cache
def _shipped_gear_variables() -> tuple[FmiVar, ...]:
    return gear_variables(shipped_case(GEAR_DEFAULT_CASE.removesuffix(".toml")))


# --- transmission FMU ----------------------------------------------------------------------


#: the name of a bearing FMU of the user's own in a transmission FMU's resources
BEARING_RESOURCE = "bearing.fmu"


def transmission_fields():
    """The case fields the transmission FMU exposes as parameters: all of them but the case's
    description, the run length (the host's stop time decides it) and the report's window
    (the FMU reports nothing: its host analyses its outputs). A run-up's
    ``drive.speed_profile`` is one: the master inside follows it."""
    return tuple(f for f in FIELDS if f.key not in ("case.description", "simulation.mesh_periods",
                                                    "simulation.window"))


def transmission_variables(case, bearing_fmu: str = "") -> tuple[FmiVar, ...]:
    """The variables of the transmission FMU of ``case`` (the gear-shaft structure, every
    bearing and the iterative master in one FMU): every case field of
    :func:`transmission_fields` as a parameter starting at the case's value (the naming of
    :func:`gear_parameters`), the parameter ``bearing_fmu`` (starting at ``bearing_fmu``), the
    inputs ``torque`` and ``speed`` with the parameter ``max_speed``, per bearing (named after
    it, as the gear-shaft FMU's ports) its journal state and film force, per mesh its force
    and transmission error."""
    lay = _train(case)
    names = lay.bearing_names
    params = [_field_variable(n, f, v) for n, f, v in case_parameters(case, transmission_fields())]
    meshes = len(lay.mesh_names)
    return _unique((
        *params,
        FmiVar("bearing_fmu", _P, "String", "", bearing_fmu,
               "a bearing FMU of your own for every bearing (any FMU with the contract of "
               "docs/fmu-variables.md, 'A bearing FMU of your own'; a path relative to the "
               "FMU's resources folder, or absolute); empty: the model each bearing's "
               "bearings.<name>.model names"),
        FmiVar("torque", _I, "Real", "torque", float(case["drive.torque"]),
               "input torque T on the input shaft, held over a communication step; until a "
               "host sets it, the parameter drive.torque acts"),
        FmiVar("max_speed", _P, "Real", "angular_speed", speed_profile(case).max_speed,
               "the highest input speed a host may set through the input speed: the time "
               "step is sized for it (the fastest mesh gets "
               "simulation.steps_per_mesh_period steps per period there); at least "
               "drive.speed and the highest of drive.speed_profile", **_POS),
        FmiVar("speed", _I, "Real", "angular_speed", float(case["drive.speed"]),
               "input shaft speed Omega reached at the end of the next communication step: "
               "over a step the speed goes linearly from its value at the step's start to "
               "this one (the angle its integral; the ramp's inertia, the unbalances and each "
               "bearing at its shaft's speed as in a run-up), then stays. Set in "
               "initialisation, it is the parameter drive.speed (the static solution's "
               "speed); until a host sets it, drive.speed and drive.speed_profile act. At "
               "most max_speed", **_POS),
        *(FmiVar(f"{n}_{b}", _O, "Real", _STATE_TEXT[n][0], 0.0, _STATE_TEXT[n][1].format(b=b))
          for b in names for n in STATE_NAMES),
        *(FmiVar(f"{n}_{b}", _O, "Real", "force", 0.0,
                 f"bearing {b}: film force on the journal along {n[-1]} (global frame)")
          for b in names for n in FORCE_NAMES),
        *_step_output_variables(lay)[:2 * meshes],
        FmiVar("iterations", _O, "Integer", "", 0,
               "coupled iterations of the master in the last communication step (the static "
               "solution's before the first step)"),
        FmiVar("steps", _O, "Integer", "", 0,
               "internal Newmark steps taken since the start (each no longer than the case's "
               "time step)"),
    ), case)


def transmission_output_names(case) -> list[str]:
    """The transmission FMU's Real outputs in the order of its variables: each bearing's
    journal state, each bearing's film force, each mesh's force then transmission error."""
    lay = _train(case)
    return [*journal_output_names(lay),
            *(f"{n}_{b}" for b in lay.bearing_names for n in FORCE_NAMES),
            *step_output_names(lay)[:2 * len(lay.mesh_names)]]


def bearing_component(bearing: str) -> str:
    """The name of bearing ``bearing``'s FMU instance in a system (an SSP component):
    ``bearing<name>`` for a name that starts with a digit (the paper's ``bearing1`` ...),
    else ``bearing_<name>`` (``bearing_in_a``)."""
    return f"bearing{bearing}" if bearing[:1].isdigit() else f"bearing_{bearing}"


def connections(case, gear: str = "gear_shaft", bearing=bearing_component) -> list[tuple]:
    """The wiring of the system of ``case``'s gear train: ``(from instance, output, to
    instance, input)`` for every connection, plain output -> input, bearing by bearing in the
    layout's order (instance names: ``gear`` and ``bearing(name)`` for each bearing,
    :func:`bearing_component` by default). The journal state and the shaft speed go to each
    bearing FMU; its force, stiffness, damping and evaluation state come back."""
    out = []
    for b in bearing_names(case):
        comp = bearing(b)
        out += [(gear, f"{n}_{b}", comp, n) for n in STATE_NAMES]
        out.append((gear, f"omega_{b}", comp, "omega"))
        out += [(comp, n, gear, f"{n}_{b}") for n in BEARING_OUTPUTS]
    return out
