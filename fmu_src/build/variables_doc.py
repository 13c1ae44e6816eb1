"""``docs/fmu-variables.md``, rendered from the contract (:mod:`fmu_src.contract`).

``python -m fmu_src.build.variables_doc > docs/fmu-variables.md``; a test keeps the two in sync.
"""

from __future__ import annotations

from bearing_fmu import MODELS
from fmu_src.contract import bearing_fmu_name
from fmu_src.contract import (
    bearing_variables,
    connections,
    gear_variables,
    transmission_variables,
)

__all__ = ["ACCURACY", "document", "markdown_table"]


def _start(v) -> str:
    if v.causality in ("output", "calculatedParameter"):
        return "-"
    if v.type == "String":
        return f'"{v.start}"'
    if v.type == "Boolean":
        return str(v.start).lower()
    return f"{v.start:g}"


def _bounds(v) -> str:
    parts = []
    if v.minimum is not None:
        parts.append(f"{'>' if v.exclusive_minimum else '>='} {v.minimum:g}")
    if v.maximum is not None:
        parts.append(f"<= {v.maximum:g}")
    if v.choices:
        parts.append(" or ".join(str(c) if c != "" else '""' for c in v.choices))
    return ", ".join(parts) or "-"


def markdown_table(variables=None) -> str:
    """A contract as a Markdown table (default: the bearing FMUs')."""
    variables = bearing_variables() if variables is None else variables
    lines = ["| name | causality | type | unit | start | allowed | description |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for v in variables:
        lines.append(f"| `{v.name}` | {v.causality} | {v.type} | {v.unit or '-'} | {_start(v)} "
                     f"| {_bounds(v)} | {v.description} |")
    return "\n".join(lines)


#: the output of ``python -m orchestrator.studies.coupling_accuracy`` (its command line is the
#: table's last line; ``tests/orchestrator/studies/test_coupling_accuracy.py`` checks that it has
#: the study's columns and default arguments): pasted when the physics or the study changes
ACCURACY = """\
Case `baguet2010_spur`, 32 mesh periods from the static start, dt = T_mesh / 32 = 2.32366e-05 s; bearing 1's orbit (iterative master at dt): peak-to-peak 2.00e-05 m along s, 8.72e-06 m along t. E [%] = bearing 1's largest journal position difference (s or t, at the instants n dt) / the reference orbit's larger peak-to-peak; columns "lag 0", "lag 1": against the iterative master at the same step.

| step [s] | steps / mesh period | lag 0 | lag 1 | lag 0, step x (1 - 1e-06) | lag 1, step x (1 - 1e-06) | lag 0 vs iterative at dt | lag 1 vs iterative at dt | iterative vs iterative at dt |
| --- | --- | --- | --- | --- | --- | --- | --- | --- |
| dt = 2.324e-05 | 32 | 7.21 | 24.42 | 7.21 | 24.42 | 7.21 | 24.42 | 0.00 |
| dt/2 = 1.162e-05 | 64 | 1.37 | 5.51 | 1.37 | 5.51 | 5.14 | 9.20 | 3.81 |
| dt/4 = 5.809e-06 | 128 | 0.35 | 1.41 | 0.35 | 1.41 | 4.74 | 5.77 | 4.40 |
| dt/8 = 2.905e-06 | 256 | 0.09 | 0.36 | 0.09 | 0.36 | 4.65 | 4.91 | 4.56 |

Observed order p of the coupling error E ~ dt^p (same step, last halving): lag 0 1.99, lag 1 1.96.

Printed by `python -m orchestrator.studies.coupling_accuracy baguet2010_spur --periods 32 --levels 4 --detune 1e-06`.
"""

_HEADER = """# FMU variables

Generated from `fmu_src/contract.py` (`python -m fmu_src.build.variables_doc > docs/fmu-variables.md`);
a test keeps the two in sync. Global frame (s, t, z) of the gear system (s from the pinion
centre to the gear centre, z along the shafts, t = z x s), SI units. Build the FMUs with
`gsb build-fmus [CASE]` (`fmu_src/build/fmus.py`); every built FMU passes `fmpy validate`.

## Conventions and wiring

- A case describes a parallel-axis gear train (`docs/case-files.md`): named shafts, gears,
  meshes and bearings. The gear-shaft FMU of a train has one group of ports per bearing, each
  suffixed with the bearing's name (`F_s_<bearing>`, `s_<bearing>`, `omega_<bearing>`, ...),
  the outputs `mesh_force_<mesh>` and `transmission_error_<mesh>` per mesh and `u_<gear>`,
  `v_<gear>` per gear; a system has one bearing FMU instance per bearing, of the bearing's own
  model, named `bearing<name>` (`bearing_<name>` for a name that starts with a letter). The
  paper's cases name their bearings `1` ... `4`: ports `F_s_1` ..., instances `bearing1` ...
- Each shaft turns about +z or -z (the input shaft about +z at the input speed omega; a mesh
  reverses the direction, at the ratio of its teeth): in the paper's case the pinion shaft
  (bearings 1, 2) about +z at omega, the gear shaft (bearings 3, 4) about -z at omega z1 / z2.
  A bearing FMU works in its own local frame: its parameter `rotation_sign` is +1 on a shaft
  turning about +z and -1 on one turning about -z (the local frame is mirrored so that the
  film model always sees the journal turning about its +z), and `frame_angle` is 0 (local x
  along s). The gear-shaft FMU publishes both per bearing (`rotation_sign_<bearing>`,
  `frame_angle_<bearing>`, calculated parameters) and the shaft speeds as outputs
  (`omega_<bearing>`).
- The system is wired by plain output -> input connections, nothing computed in between
  (`fmu_src.contract.connections`; `gsb export-ssp` writes them into an SSP file). For the
  paper's bearing 1 (every bearing alike, with its own suffix and instance):

| from | output | to | input |
| --- | --- | --- | --- |
{wiring}

- The gear-shaft FMU builds each bearing's affine law (paper Eq. 17) from those inputs:
  `F(X, Xdot) = F - Kb (X - X_eval) - Cb (Xdot - Xdot_eval)`, the force, stiffness and damping
  the bearing FMU gave at the journal state `X_eval` it echoes (`s_eval`, ...). Whatever the
  master, the law is a correct linearisation about a state the structure passed through; how
  far that state lags is the master's coupling error (next section).
- Values are checked when set: a value out of its bounds (column "allowed"), a non-finite
  number or a choice not listed is refused by fmi2SetReal/SetInteger with fmi2Error, the value
  and the limit in the log, and the variable keeps its previous value. modelDescription.xml
  declares the bounds as enforced: a strict one ("> 0", which FMI cannot write) as `min` =
  the smallest double above it (5e-324), its description ending in "(> 0)".
- An output that cannot be computed (a journal outside the clearance, a law that is not
  finite, a static solution or a step that does not converge) makes the read return
  fmi2Error, the reason in the log (the values read are NaN); a bearing FMU's fmi2DoStep at
  such inputs returns fmi2Discard, the reason in the log, so that a host that steps, then
  exchanges, learns it at the step.
- Every FMU's state (fmi2GetFMUstate, fmi2SerializeFMUstate) holds everything its next outputs
  depend on, the hybrid solver's warm start included: a restored state reproduces the outputs
  bit for bit.

## Masters

- Iterative, with rollback (`gsb run`, `orchestrator.coupling.master`): each step, the gear-shaft FMU
  steps with the laws linearised at the last iterate, the bearings are evaluated at the new
  journal states, and the step is redone from a saved FMU state (fmi2GetFMUstate /
  fmi2SetFMUstate) until film force and law agree to the case's tolerance: Newton-Raphson on
  the bearing nonlinearity, equal to a monolithic solution to that tolerance.
- Non-iterative (hosts without rollback, running the SSP archive of `gsb export-ssp`): each
  step the gear-shaft FMU steps once with the laws it was given, and nothing compares them
  with the bearings at the new journal states. Two schemes, by when the bearing outputs reach
  the gear-shaft FMU:
  - lag 0, Gauss-Seidel (OMSimulator, which orders the FMUs by their declared dependencies):
    the bearings are evaluated at the journal states X_n of the step just taken, so the
    gear-shaft FMU steps from X_n with the laws linearised at X_n (the iterative master's
    first pass, accepted as it is). `tests/system/test_omsimulator.py` reproduces OMSimulator
    3.0's trajectories to 3.5e-12 with the emulation below, lag 0. OMSimulator 3.0 takes the
    step of co-simulation FMUs from its API only (`SSP(path).instantiate()`, then
    `setFixedStepSize(dt)`): the SSD's default experiment gives it the start and stop times,
    and its solver annotation (`oms:SimulationInformation` with a `stepSize`) would put the
    FMUs into a model-exchange system, which co-simulation FMUs refuse. The archive names
    the gear-shaft component so that no segment of its variables' names equals it
    (`fmu_src.build.ssp:gear_component`): OMSimulator 3.0 drops such segments, and the
    paper's shaft `gear_shaft` once made it crash;
  - lag 1, Jacobi (ecos, libcosim, and most fixed-step masters): every FMU steps with the
    inputs of the last exchange, then outputs are exchanged. The bearing outputs exchanged
    after step n were evaluated at the journal states of step n - 1, so the gear-shaft FMU
    steps from X_n with laws linearised at X_n-1. `tests/system/test_ecos.py` reproduces
    ecos's trajectories to 1e-12 with an emulation of exactly this scheme
    (`orchestrator.studies.coupling_accuracy.non_iterative`, which also runs lag 0).

  A lag-L law is the bearing's first-order expansion about X_n-L used at X_n+1: its force
  error is (1/2) F'' (X_n+1 - X_n-L)^2, second order in the step, and four times larger for
  lag 1 than for lag 0. Affine bearings (`linear`, `lumped`) make both schemes exact.
- Initialisation: in initialisation mode the gear-shaft FMU's outputs are the static solution
  for its current law inputs, so a master's initialisation loop is a Newton iteration on X0;
  from the law inputs' start values (journals at the centre) it overshoots the clearance. The
  SSP archive of `gsb export-ssp` therefore carries the static solution X0 that `gsb`'s master
  found as start values of the connected inputs: a non-iterative master starts in equilibrium
  (ecos reproduces X0 to 6e-15).

### Accuracy of a non-iterative master against the step

How far a non-iterative master's journal orbit is from `gsb run`'s (iterative, converged to
the case's tolerance every step), for the paper's spur case with hybrid bearings, computed
with the in-process physics emulating the two schemes exactly as the hosts run the FMUs:

{accuracy}

Reading it:

- Columns "lag 0", "lag 1": the coupling error alone, against `gsb run` at the same step
  (`--set simulation.steps_per_mesh_period=N` with N the second column). From T_mesh / 64 on
  it falls as dt^2, lag 1's four times lag 0's.
- Columns "step x (1 - 1e-06)": the same at a step 1e-6 shorter, as a tool user may type
  it. A contact line enters or leaves the path of contact exactly at a step's end at
  T_mesh / 32; off by a hair, the event drifts through the step's end. The structure takes an
  event closer than 1e-3 of a step to the step's end at the end (no shorter sub-step: Newmark's
  acceleration update would amplify round-off by 4 / h^2), so the result does not depend on
  the step's last digits.
- The last three columns compare with `gsb run` of the shipped case (T_mesh / 32), what a
  tool user is likely to hold as the reference: the iterative master itself moves by about
  4.5 % of the orbit between T_mesh / 32 and T_mesh / 256 (the time discretisation: `gsb run`
  notes that the 4366 Hz mesh mode gets 9.9 steps per period at T_mesh / 32), so compare with
  `gsb run` at the step the tool used.

Which step to give a tool: for a coupling error below about 2 % of the orbit, T_mesh / 64
(dt/2) with lag 0 (OMSimulator), T_mesh / 128 (dt/4) with lag 1 (ecos, libcosim); below
0.5 %: T_mesh / 128 and T_mesh / 256. Export the archive with that step
(`gsb export-ssp CASE --set simulation.steps_per_mesh_period=N`: its step size, printed with
the command, is T_mesh / N to the last digit) and give the host that number. For results that
do not depend on the host's coupling, use the transmission FMU (`gsb export-fmu CASE --dest DIR`): one FMU
with the iterative master inside, which gives `gsb run`'s result at the step the tool takes
in any tool (the coupling exact; the step's time discretisation remains, last column).

## A bearing FMU of your own

`gsb run CASE --bearing-fmu MY.fmu` (or `orchestrator.coupling.fmi.FmuBearings`) accepts any
algebraic FMU (outputs follow inputs without a doStep) with this minimal contract:

- Real inputs `s`, `t` [m] and `s_dot`, `t_dot` [m/s]: the journal-centre state, global frame;
- Real outputs `F_s`, `F_t` [N]: the film force on the journal, global frame.

Optional: an input `omega` gets the shaft speed magnitude [rad/s]; parameters named as in the
table below (`D`, `L`, `C`, `mu`, `frame_angle`, `rotation_sign`, the model options) get the
case's values (mirror your model for `rotation_sign` -1: the gear shaft turns about -z). With
all eight outputs `K_ss` ... `C_tt` they are used as they are; without them the master takes
Kb and Cb by central differences of the force (steps 1e-5 C on positions and 1e-5 C omega on
velocities: 8 more evaluations per call; round-off about 1e-12 of Kb). An FMU built with
pythonfmu gets this package's native layer (statuses, a clean exit, the loader for C/C++
hosts) from `fmu_src.build.fmus.patch_fmu`. Direct wiring (an SSP, ecos) needs the full bearing
contract below: the gear-shaft FMU reads Kb, Cb and the evaluation state as inputs.

## Bearing FMUs

Every bearing FMU ({fmus}) has exactly these variables; the model options (`nodes`, ...)
are generated from the options the registered models declare, and each FMU ignores the
options of the other models. Outputs are computed when read, so they follow new inputs
without a doStep (algebraic FMUs: every output depends on every input). `BearingLinear` runs
the hybrid model until fmi2ExitInitializationMode and then freezes its 8 coefficients at the
journal state it has then (the static position; paper Sec. 3.3).

"""

_GEAR = """
## Gear-shaft FMU (GearShaft)

The structural slave (`fmu_src/slaves/gear_shaft.py` around `gear_fmu.structure.Structure`):
Timoshenko shafts, each mesh's distributed mesh element and the Newmark/Newton/contact step.
It carries its case (`resources/case.toml`, the shipped paper case unless `gsb build-fmus CASE`
built it for another), whose gear train gives its ports: one group per bearing, per mesh and
per gear, named after them (previous section). The case's structural fields are its
parameters, starting at the case's values, named by their case keys (`gears.pinion.module`;
where each bearing sits, `bearings.'1'.shaft` and `bearings.'1'.position`, a name that is no
identifier quoted as FMI's structured names want it; a list field one parameter per entry,
`shafts.pinion_shaft.outer_diameter[1]`). A case of another train (other names of bearings,
meshes, gears or shafts) needs the gear-shaft FMU built for it (`gsb build-fmus CASE`; `gsb
run` builds it once per train beside the others, as `GearShaft_<digest>.fmu`). It imports
nothing from the master package `orchestrator`.

Behaviour:

- Initialisation mode: outputs are the STATIC solution (velocities zero, constant loads) for
  the current inputs, solved when an output is read after an input changed. The support loads
  (calculated parameters) are the loads on stiff supports, a first guess of the static
  solution. The start values of the law inputs (isotropic 1e8 N/m and 1e4 N s/m, no force,
  about the centre) make a stand-alone `fmpy simulate` run sensible; in a system, start from
  X0 (previous section).
- `fmi2ExitInitializationMode`: if no static solution was computed yet, it is computed for the
  current inputs; the modal damping is rebuilt on the modes with the symmetric part of the
  current Kb (`Structure.set_damping_reference`).
- `fmi2DoStep(t, dt)`: one Newmark step from t (the FMU's time) to t + dt with the current
  laws. The outputs do not depend directly on the inputs in step mode (no feedthrough): they
  change at doStep. A step that cannot be computed (a Newton iteration that does not
  converge, a step of more than 100 mesh periods) returns fmi2Discard (reason in the log);
  the outputs then read fmi2Error and further steps are refused until `fmi2SetFMUstate`
  returns to a saved state.
- `fmi2GetFMUstate` / `fmi2SetFMUstate` / `fmi2SerializeFMUstate` save and restore the
  structural state (t, X, Xdot, Xddot, contact set, mesh outputs), the inputs, the parameters
  and the outputs exactly. Serialised states are numeric arrays in an npz archive with a
  format version and a kind (`fmu_src/state_codec.py`), never a pickle: bytes that are not
  such a state of this FMU are refused by `fmi2DeSerializeFMUstate` with fmi2Error (the
  reason in the log), the instance intact.

"""

_TRANSMISSION = """
## Transmission FMU (`gsb export-fmu CASE`)

The whole system in one FMU, for tools that do not iterate FMUs (libcosim, OMSimulator, ecos
and most fixed-step masters): the gear-shaft structure of the case's gear train, its bearings,
each of the model its `bearings.<name>.model` names (any registered model: {models}), and this package's iterative master
inside `fmi2DoStep` (`orchestrator/coupling/transmission.py`). `gsb export-fmu CASE --dest
DIR` writes `DIR/<case>.fmu`, carrying the case (`resources/case.toml`) and the code it runs,
master included. It gives `gsb run`'s numbers at the same step in any FMI host, bit for bit at
the case's step.

- Parameters: every case field but `case.description` and `simulation.mesh_periods` (the
  host's stop time decides the run's length), named as the gear-shaft FMU names them; a list
  field one parameter per entry (`shafts.pinion_shaft.outer_diameter[1]`, `meshes.mesh.gears[2]`). A new value rebuilds the
  system.
- Input `torque` [N.m]: the input torque on the input shaft, held over each communication
  step; until a host sets it, the parameter `drive.torque` acts. The mesh's contact
  compliance stays linearised at `drive.torque`.
- Input `speed` [rad/s]: a run-up driven by the host's own drive model. The speed the input
  shaft reaches at the end of the next communication step: over the step it goes linearly
  from its value at the step's start, the angle its integral, with the ramp's inertia, the
  unbalances at their acceleration and each bearing at its shaft's speed, as a case's
  `drive.speed_profile` does (docs/equations.md "Run-ups"); then it stays until set again.
  A host that sets, before each step, the speed a profile reaches at the step's end gets
  `gsb run`'s run-up of that profile (to round-off). Set in initialisation, it is the
  parameter `drive.speed` (X0's speed); until a host sets it, `drive.speed` and
  `drive.speed_profile` act. Refused (fmi2Error at the fmi2SetReal, the reason in the log):
  above the parameter `max_speed` (the time step is sized for it: set it before
  initialisation; by default the case's highest speed), at 0 or below, and a change of
  speed for a case with linear bearings (built for one speed).
- Initialisation mode: the outputs are the static solution X0 of the current parameters and
  torque (velocities zero), solved when first read or at fmi2ExitInitializationMode, which
  then builds the modal damping as a run does.
- `fmi2DoStep(t, h)`: `n = ceil(h / (dt (1 + 1e-4)))` equal coupled steps of `h / n`, dt the
  case's step (`DefaultExperiment` carries it, and the case's run length as its stop time): a
  step within 1e-4 of dt (libcosim's whole nanoseconds) is taken as it comes, a longer one cut
  into steps no longer than dt. `t` must be the FMU's time (to 1e-9). A step that fails (a
  journal leaving its clearance, the coupled iteration not converging) returns fmi2Discard,
  the reason in the log; the outputs then read fmi2Error and no further step is taken until a
  state is set.
- States: fmi2GetFMUstate / fmi2SetFMUstate / fmi2SerializeFMUstate hold the master's
  checkpoint (structure, bearing warm starts, laws), the parameters, the torque, the speed
  (with the ramp it follows) and the time; a serialised state set into another instance
  solves that instance's X0 first (as a resumed run does), then continues bit for bit.
- Outputs: `iterations` counts the master's coupled iterations in the last communication
  step, `steps` the internal steps so far.

Its variables for the shipped paper case (parameters with the case's values as start; per
bearing and per mesh of another train, the same outputs with its names):

"""


def document() -> str:
    """The text of docs/fmu-variables.md."""
    fmus = ", ".join(bearing_fmu_name(m) for m in MODELS)
    from fmu_src.case import shipped_case

    paper = shipped_case("baguet2010_spur")
    wiring = "\n".join(f"| `{a}` | `{o}` | `{b}` | `{i}` |" for a, o, b, i in connections(paper)
                       if "bearing1" in (a, b))
    transmission = transmission_variables(paper)
    return (_HEADER.format(fmus=fmus, wiring=wiring, accuracy=ACCURACY.rstrip("\n"))
            + markdown_table(bearing_variables()) + "\n"
            + _GEAR + markdown_table(gear_variables()) + "\n"
            + _TRANSMISSION.format(models=", ".join(MODELS))
            + markdown_table(transmission) + "\n")


if __name__ == "__main__":
    print(document(), end="")
