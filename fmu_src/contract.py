"""The FMI variable contract of the bearing FMUs (one source of truth).

Every bearing FMU (hybrid, short, fd, linear, lumped) exposes exactly these variables, so a system
swaps one for another by file name alone. The FMU works in the GLOBAL frame (s, t) of the gear
system; its parameters ``frame_angle`` and ``rotation_sign`` place the bearing's local frame
(:class:`bearing_fmu.frames.LocalFrame`) in which the film model runs. Units are SI.

The table is rendered into ``docs/fmu-variables.md`` by :func:`markdown_table` and into each
FMU's modelDescription.xml (units, descriptions, start values) by :mod:`fmu_src.build`.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["BEARING_VARIABLES", "UNITS", "FmiVar", "markdown_table"]


@dataclass(frozen=True)
class FmiVar:
    """One FMI 2.0 scalar variable."""

    name: str
    causality: str  # parameter | input | output
    type: str  # Real | Integer
    unit: str  # "" for dimensionless
    start: float
    description: str


#: unit name -> SI base-unit exponents (kg, m, s) for <UnitDefinitions>
UNITS = {
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N/m": {"kg": 1, "s": -2},
    "N.s/m": {"kg": 1, "s": -1},
    "rad": {},
    "rad/s": {"s": -1},
    "Pa.s": {"kg": 1, "m": -1, "s": -1},
    "1": {},
}

_P, _I, _O = "parameter", "input", "output"

BEARING_VARIABLES: tuple[FmiVar, ...] = (
    # bearing data (paper Table 3: pinion bearings as start values)
    FmiVar("D", _P, "Real", "m", 0.070, "bearing diameter D = 2R"),
    FmiVar("L", _P, "Real", "m", 0.050, "bearing length L"),
    FmiVar("C", _P, "Real", "m", 150e-6, "radial clearance C"),
    FmiVar("mu", _P, "Real", "Pa.s", 0.0288, "dynamic viscosity of the lubricant"),
    FmiVar("frame_angle", _P, "Real", "rad", 0.0,
           "angle from the global s axis to the bearing's local x axis"),
    FmiVar("rotation_sign", _P, "Integer", "", 1,
           "+1 if the shaft turns about +z, -1 if about -z (local frame mirrored)"),
    FmiVar("n_theta", _P, "Integer", "", 192,
           "circumferential nodes (hybrid n, finite-difference n_theta); unused by other models"),
    FmiVar("n_xi", _P, "Integer", "", 32, "axial intervals (finite-difference model only)"),
    FmiVar("k_lumped", _P, "Real", "N/m", 1e8, "isotropic stiffness (lumped-spring model only)"),
    FmiVar("c_lumped", _P, "Real", "N.s/m", 0.0, "isotropic damping (lumped-spring model only)"),
    # journal state at the bearing node, global frame
    FmiVar("s", _I, "Real", "m", 0.0, "journal-centre displacement along s (global frame)"),
    FmiVar("t", _I, "Real", "m", 0.0, "journal-centre displacement along t (global frame)"),
    FmiVar("s_dot", _I, "Real", "m/s", 0.0, "journal-centre velocity along s"),
    FmiVar("t_dot", _I, "Real", "m/s", 0.0, "journal-centre velocity along t"),
    FmiVar("omega", _I, "Real", "rad/s", 325.0, "shaft speed magnitude (> 0)"),
    # film force on the journal and its linearisation, global frame
    FmiVar("F_s", _O, "Real", "N", 0.0, "film force on the journal along s"),
    FmiVar("F_t", _O, "Real", "N", 0.0, "film force on the journal along t"),
    FmiVar("K_ss", _O, "Real", "N/m", 0.0, "stiffness -dF_s/ds"),
    FmiVar("K_st", _O, "Real", "N/m", 0.0, "stiffness -dF_s/dt"),
    FmiVar("K_ts", _O, "Real", "N/m", 0.0, "stiffness -dF_t/ds"),
    FmiVar("K_tt", _O, "Real", "N/m", 0.0, "stiffness -dF_t/dt"),
    FmiVar("C_ss", _O, "Real", "N.s/m", 0.0, "damping -dF_s/ds_dot"),
    FmiVar("C_st", _O, "Real", "N.s/m", 0.0, "damping -dF_s/dt_dot"),
    FmiVar("C_ts", _O, "Real", "N.s/m", 0.0, "damping -dF_t/ds_dot"),
    FmiVar("C_tt", _O, "Real", "N.s/m", 0.0, "damping -dF_t/dt_dot"),
    FmiVar("eccentricity", _O, "Real", "1", 0.0, "eccentricity ratio e/C of the journal"),
    FmiVar("n_solves", _O, "Integer", "", 0,
           "film-force evaluations so far (Reynolds solves for film models)"),
)

#: names of the output matrices in row-major order, local to global
FORCE_NAMES = ("F_s", "F_t")
STIFFNESS_NAMES = ("K_ss", "K_st", "K_ts", "K_tt")
DAMPING_NAMES = ("C_ss", "C_st", "C_ts", "C_tt")
STATE_NAMES = ("s", "t", "s_dot", "t_dot")


def markdown_table(variables=BEARING_VARIABLES) -> str:
    """The contract as a Markdown table (for docs/fmu-variables.md)."""
    lines = ["| name | causality | type | unit | start | description |",
             "| --- | --- | --- | --- | --- | --- |"]
    for v in variables:
        lines.append(f"| `{v.name}` | {v.causality} | {v.type} | {v.unit or '-'} | {v.start:g} | "
                     f"{v.description} |")
    return "\n".join(lines)


_DOC_HEADER = """# Bearing FMU variables

Generated from `fmu_src/contract.py` (`python -m fmu_src.contract > docs/fmu-variables.md`);
a test keeps the two in sync. Every bearing FMU (BearingHybrid, BearingShort, BearingFd,
BearingLinear, BearingLumped) has exactly these variables. Global frame (s, t), SI units; the
parameters `frame_angle` and `rotation_sign` place the bearing's local frame, in which the film
model runs (`bearing_fmu/frames.py`). Outputs are computed when read, so they follow new inputs
without a doStep. A failed evaluation (eccentricity >= 1, bad parameters) is logged with status
error, gives NaN outputs, and the next doStep returns discard.

"""


def document() -> str:
    """The text of docs/fmu-variables.md."""
    return _DOC_HEADER + markdown_table() + "\n"


if __name__ == "__main__":
    print(document(), end="")
