"""The FMI variable contracts of the FMUs (one source of truth).

:data:`BEARING_VARIABLES`: every bearing FMU (one per model of :data:`bearing_fmu.MODELS`)
exposes exactly these variables, so a system swaps one for another by file name alone. The FMU works
in the GLOBAL frame (s, t) of the gear system; its parameters ``frame_angle`` and
``rotation_sign`` place the bearing's local frame (:class:`bearing_fmu.frames.LocalFrame`) in
which the film model runs. Units are SI.

:data:`GEAR_VARIABLES`: the gear-shaft FMU (``GearShaft``): per bearing j = 1..4 an affine
bearing law ``F_j = F0_j - Kb_j X_j - Cb_j Xdot_j`` in (inputs), the journal state X_j, Xdot_j
out, plus mesh and gear outputs (DESIGN.md section 4).

The layouts of the 40 law inputs and the 16 journal outputs are defined once here
(:func:`law_input_names`, :func:`pack_laws`, :func:`unpack_laws`, :func:`unpack_journal`).
Units are the dimensions of :mod:`fmu_src.units`. The tables are rendered into
``docs/fmu-variables.md`` by :func:`document` and into each FMU's modelDescription.xml (units,
descriptions, start values) by :mod:`fmu_src.build`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bearing_fmu import MODELS, model_class
from bearing_fmu.affine import AffineLaws
from fmu_src.units import symbol

__all__ = ["BEARING_VARIABLES", "GEAR_DEFAULT_CASE", "GEAR_VARIABLES", "FmiVar",
           "bearing_option_keys", "document", "markdown_table", "pack_laws", "unpack_journal",
           "unpack_laws"]


@dataclass(frozen=True)
class FmiVar:
    """One FMI 2.0 scalar variable (``dimension``: a key of :data:`fmu_src.units.DIMENSIONS`,
    "" for integers, strings and flags)."""

    name: str
    causality: str  # parameter | calculatedParameter | input | output
    type: str  # Real | Integer | String
    dimension: str
    start: float | int | str
    description: str

    @property
    def unit(self) -> str:
        """The unit symbol (:mod:`fmu_src.units`), "" for none."""
        return symbol(self.dimension) if self.dimension else ""


_P, _CP, _I, _O = "parameter", "calculatedParameter", "input", "output"

def _paper_bearing():
    """Start values of the bearing data: bearing 1 of the paper's spur case (Table 3)."""
    from fmu_src.case import load_case

    case = load_case("baguet2010_spur")
    return {k: case[f"bearings.{k}"][0] for k in ("diameter", "length", "clearance",
                                                   "viscosity")}


def _option_variables() -> tuple[FmiVar, ...]:
    """One parameter per option of the registered bearing models (:mod:`fmu_src.case` merges
    them the same way), so every bearing FMU has the same variables."""
    from fmu_src.case import model_option_fields

    out = []
    for f in model_option_fields():
        key = f.key.split(".", 1)[1]
        if f.kind == "count":
            out.append(FmiVar(key, _P, "Integer", "", int(f.default), f.doc))
        else:
            out.append(FmiVar(key, _P, "Real", f.kind, float(f.default), f.doc))
    return tuple(out)


_B = _paper_bearing()
#: The variables of every bearing FMU (module docstring).
#:
#: :meta hide-value:
BEARING_VARIABLES: tuple[FmiVar, ...] = (
    # bearing data (start values: the paper's pinion bearing, Table 3)
    FmiVar("D", _P, "Real", "length", _B["diameter"], "bearing diameter D = 2R"),
    FmiVar("L", _P, "Real", "length", _B["length"], "bearing length L"),
    FmiVar("C", _P, "Real", "length", _B["clearance"], "radial clearance C"),
    FmiVar("mu", _P, "Real", "viscosity", _B["viscosity"],
           "dynamic viscosity of the lubricant"),
    FmiVar("frame_angle", _P, "Real", "angle", 0.0,
           "angle from the global s axis to the bearing's local x axis"),
    FmiVar("rotation_sign", _P, "Integer", "", 1,
           "+1 if the shaft turns about +z, -1 if about -z (local frame mirrored)"),
    *_option_variables(),
    # journal state at the bearing node, global frame
    FmiVar("s", _I, "Real", "length", 0.0, "journal-centre displacement along s (global frame)"),
    FmiVar("t", _I, "Real", "length", 0.0, "journal-centre displacement along t (global frame)"),
    FmiVar("s_dot", _I, "Real", "velocity", 0.0, "journal-centre velocity along s"),
    FmiVar("t_dot", _I, "Real", "velocity", 0.0, "journal-centre velocity along t"),
    FmiVar("omega", _I, "Real", "angular_speed", 325.0, "shaft speed magnitude (> 0)"),
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
    FmiVar("eccentricity", _O, "Real", "dimensionless", 0.0,
           "eccentricity ratio e/C of the journal"),
    FmiVar("n_solves", _O, "Integer", "", 0,
           "film-force evaluations so far (Reynolds solves for film models)"),
)


def bearing_option_keys() -> tuple[str, ...]:
    """Names of the bearing FMU parameters that are model options (all registered models)."""
    return tuple(sorted({o.key for name in MODELS for o in model_class(name).options},
                        key=[v.name for v in BEARING_VARIABLES].index))


#: names of the output matrices in row-major order, local to global
FORCE_NAMES = ("F_s", "F_t")
STIFFNESS_NAMES = ("K_ss", "K_st", "K_ts", "K_tt")
DAMPING_NAMES = ("C_ss", "C_st", "C_ts", "C_tt")
STATE_NAMES = ("s", "t", "s_dot", "t_dot")


#: the case file shipped in the gear-shaft FMU's resources (``case_file`` empty)
GEAR_DEFAULT_CASE = "baguet2010_spur.toml"
#: the gear-shaft FMU's bearing numbering (1, 2 pinion shaft; 3, 4 gear shaft)
BEARINGS = (1, 2, 3, 4)
#: per-bearing affine-law inputs in the order of the FMU's variables (row-major matrices)
LAW_NAMES = ("F0_s", "F0_t", *STIFFNESS_NAMES, *DAMPING_NAMES)
#: start values of the law inputs: isotropic 1e8 N/m, 1e4 N s/m, F0 = 0 (stand-alone runs)
LAW_START = {"F0_s": 0.0, "F0_t": 0.0, "K_ss": 1e8, "K_st": 0.0, "K_ts": 0.0, "K_tt": 1e8,
             "C_ss": 1e4, "C_st": 0.0, "C_ts": 0.0, "C_tt": 1e4}
_LAW_TEXT = {
    "F0_s": ("force", "bearing {j}: affine-law force at X = 0, Xdot = 0, along s"),
    "F0_t": ("force", "bearing {j}: affine-law force at X = 0, Xdot = 0, along t"),
    "K_ss": ("stiffness", "bearing {j}: affine-law stiffness -dF_s/ds"),
    "K_st": ("stiffness", "bearing {j}: affine-law stiffness -dF_s/dt"),
    "K_ts": ("stiffness", "bearing {j}: affine-law stiffness -dF_t/ds"),
    "K_tt": ("stiffness", "bearing {j}: affine-law stiffness -dF_t/dt"),
    "C_ss": ("damping", "bearing {j}: affine-law damping -dF_s/ds_dot"),
    "C_st": ("damping", "bearing {j}: affine-law damping -dF_s/dt_dot"),
    "C_ts": ("damping", "bearing {j}: affine-law damping -dF_t/ds_dot"),
    "C_tt": ("damping", "bearing {j}: affine-law damping -dF_t/dt_dot"),
}
_STATE_TEXT = {
    "s": ("length", "bearing {j}: journal-centre displacement along s (global frame)"),
    "t": ("length", "bearing {j}: journal-centre displacement along t (global frame)"),
    "s_dot": ("velocity", "bearing {j}: journal-centre velocity along s"),
    "t_dot": ("velocity", "bearing {j}: journal-centre velocity along t"),
}


def law_input_names() -> list[str]:
    """The 40 law inputs of the gear-shaft FMU: bearing-major, :data:`LAW_NAMES` within."""
    return [f"{n}_{j}" for j in BEARINGS for n in LAW_NAMES]


def journal_output_names() -> list[str]:
    """The 16 journal outputs: bearing-major, (s, t, s_dot, t_dot) within (journal_states)."""
    return [f"{n}_{j}" for j in BEARINGS for n in STATE_NAMES]


def support_load_names() -> list[str]:
    """The 8 support loads: bearing-major, (s, t) within."""
    return [f"support_load_{a}_{j}" for j in BEARINGS for a in ("s", "t")]


def pack_laws(laws: AffineLaws, out: np.ndarray) -> None:
    """Write four affine laws (Eq. 17, global frame) into ``out``, the 40 law inputs in the
    order of :func:`law_input_names` (float64, C order, any shape with 40 elements)."""
    v = out.reshape(4, 10)
    v[:, 0:2] = laws.f0
    v[:, 2:6] = np.reshape(laws.kb, (4, 4))
    v[:, 6:10] = np.reshape(laws.cb, (4, 4))


def unpack_laws(values) -> AffineLaws:
    """The four affine laws of the 40 law inputs (order of :func:`law_input_names`), as
    C-contiguous arrays F0 (4, 2), Kb (4, 2, 2), Cb (4, 2, 2)."""
    a = np.array(values, dtype=float).reshape(4, 10)
    return AffineLaws(np.ascontiguousarray(a[:, 0:2]),
                      np.ascontiguousarray(a[:, 2:6]).reshape(4, 2, 2),
                      np.ascontiguousarray(a[:, 6:10]).reshape(4, 2, 2))


def unpack_journal(values) -> np.ndarray:
    """(4, 4) journal states [s, t, s_dot, t_dot] of bearings 1-4 from the 16 journal outputs
    (order of :func:`journal_output_names`)."""
    return np.asarray(values, dtype=float).reshape(4, 4)


#: outputs of the gear-shaft FMU after the journal states (name, dimension, description)
GEAR_OUTPUTS = (
    ("mesh_force", "force", "total normal tooth load of the mesh (sum of the slice loads)"),
    ("transmission_error", "length",
     "transmission error r_b1 theta_1 + r_b2 theta_2 of the gear nodes' elastic torsion"),
    ("u_pinion", "length", "pinion node displacement along s"),
    ("v_pinion", "length", "pinion node displacement along t"),
    ("u_gear", "length", "gear node displacement along s"),
    ("v_gear", "length", "gear node displacement along t"),
)

#: The variables of the gear-shaft FMU (module docstring).
#:
#: :meta hide-value:
GEAR_VARIABLES: tuple[FmiVar, ...] = (
    FmiVar("case_file", _P, "String", "", "",
           "TOML case file (fmu_src.case) describing the gear pair, shafts and operating "
           "point; empty = the paper's spur case shipped in the FMU's resources"),
    *(FmiVar(f"{n}_{j}", _I, "Real", _LAW_TEXT[n][0], LAW_START[n],
             _LAW_TEXT[n][1].format(j=j)) for j in BEARINGS for n in LAW_NAMES),
    *(FmiVar(f"{n}_{j}", _O, "Real", _STATE_TEXT[n][0], 0.0, _STATE_TEXT[n][1].format(j=j))
      for j in BEARINGS for n in STATE_NAMES),
    *(FmiVar(n, _O, "Real", u, 0.0, d) for n, u, d in GEAR_OUTPUTS),
    FmiVar("iterations", _O, "Integer", "", 0,
           "Newton/contact iterations (linear solves) of the last step or static solution"),
    *(FmiVar(f"support_load_{a}_{j}", _CP, "Real", "force", 0.0,
             f"bearing {j}: static load of the structure on the bearing along {a} with stiff "
             "(1e12 N/m) supports (the master's first guess of the static solution)")
      for j in BEARINGS for a in ("s", "t")),
)


def _start(v: FmiVar) -> str:
    if v.causality in ("output", "calculatedParameter"):
        return "-"
    if v.type == "String":
        return f'"{v.start}"'
    return f"{v.start:g}"


def markdown_table(variables=BEARING_VARIABLES) -> str:
    """A contract as a Markdown table (for docs/fmu-variables.md)."""
    lines = ["| name | causality | type | unit | start | description |",
             "| --- | --- | --- | --- | --- | --- |"]
    for v in variables:
        lines.append(f"| `{v.name}` | {v.causality} | {v.type} | {v.unit or '-'} | {_start(v)} | "
                     f"{v.description} |")
    return "\n".join(lines)


_DOC_HEADER = """# FMU variables

Generated from `fmu_src/contract.py` (`python -m fmu_src.contract > docs/fmu-variables.md`);
a test keeps the two in sync. Global frame (s, t) of the gear system, SI units. Build the FMUs
with `gsb build-fmus` (`fmu_src/build.py`); every built FMU passes `fmpy validate`.

## Bearing FMUs

Every bearing FMU ({fmus}) has exactly these variables; the model options (`nodes`, ...)
are generated from the options the registered models declare, and each FMU ignores the
options of the other models. The parameters `frame_angle` and `rotation_sign` place the bearing's
local frame, in which the film model runs (`bearing_fmu/frames.py`). Outputs are computed when
read, so they follow new inputs without a doStep. A failed evaluation (eccentricity >= 1, bad
parameters) is logged with status error, gives NaN outputs, and the next doStep returns discard.

"""

_GEAR_HEADER = """
## Gear-shaft FMU (GearShaft)

The structural slave (`fmu_src/gear_shaft_slave.py` around `gear_fmu.structure.Structure`):
Timoshenko shafts, the gear pair's distributed mesh element and the Newmark/Newton/contact step.
It is built from the case file named by `case_file` through `fmu_src.case` and
`fmu_src.description` (the system description: case file -> physics objects, shared with the
in-process runs); it imports nothing from the master package `orchestrator`.

Inputs: per bearing j = 1..4 the affine bearing law `F_j = F0_j - Kb_j X_j - Cb_j Xdot_j`
(force of the bearing on the structure at the bearing node, global frame; `K_st_j` is the
(s, t) entry of Kb_j, row-major). Outputs: the journal state of each bearing node, the mesh
and gear-node outputs, the iteration count of the last solve. The start values (isotropic
1e8 N/m and 1e4 N s/m, F0 = 0) make a stand-alone `fmpy simulate` run sensible.

Behaviour:

- Initialisation mode: outputs are the STATIC solution (velocities zero, constant loads) for
  the current laws, solved when an output is read after an input changed. The master iterates
  the static solution through the FMU this way. The support loads (calculated parameters) are
  the loads on stiff supports, the master's first guess.
- `fmi2ExitInitializationMode`: if no static solution was computed yet, it is computed for the
  current laws (otherwise the last one read stays the initial state, as with the in-process
  structure); the modal damping is rebuilt on the modes with the symmetric part of the current
  Kb laws (`Structure.set_damping_reference`).
- `fmi2DoStep(t, dt)`: one Newmark step from t (the FMU's time) to t + dt with the current
  laws. The outputs do not depend directly on the inputs in step mode (no feedthrough): they
  change at doStep.
- Failures (Newton/contact not converged, non-finite laws, a bad case file) are logged with
  status error and the call returns a non-OK status (doStep: discard, outputs in initialisation
  mode: NaN); the instance and its host survive, and `fmi2SetFMUstate` returns to a saved state.
- `fmi2GetFMUstate` / `fmi2SetFMUstate` save and restore the structural state (t, X, Xdot,
  Xddot, contact set, mesh outputs), the laws and the outputs exactly (the modal damping
  reference is not part of the state); states serialise with pickle.

"""


def document() -> str:
    """The text of docs/fmu-variables.md."""
    from bearing_fmu import fmu_name

    fmus = ", ".join(fmu_name(m) for m in MODELS)
    return (_DOC_HEADER.format(fmus=fmus) + markdown_table(BEARING_VARIABLES) + "\n"
            + _GEAR_HEADER
            + markdown_table(GEAR_VARIABLES) + "\n")


if __name__ == "__main__":
    print(document(), end="")
