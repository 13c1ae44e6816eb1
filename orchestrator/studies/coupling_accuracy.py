"""How far a non-iterating FMI master's trajectory is from ``gsb run``'s, against the step.

    python -m orchestrator.studies.coupling_accuracy [CASE] [--periods N] [--levels L]

FMI hosts without rollback (OMSimulator, ecos, libcosim) run the exported system
(``gsb export-ssp``) non-iteratively: each step the gear-shaft FMU steps once with the bearing
laws it was given, and nobody checks them against the bearings at the new journal states.
Two schemes, emulated here with the in-process physics exactly as the FMU hosts run the FMUs
(:func:`non_iterative`; ``tests/system/test_ecos.py`` checks the lag-1 emulation against ecos
to round-off):

* lag 0, Gauss-Seidel (OMSimulator, from the FMUs' declared dependencies): the bearings are
  evaluated at the journal states X_n the gear-shaft FMU gave after step n, so step n + 1
  starts from X_n with the laws linearised at X_n;
* lag 1, Jacobi (ecos, libcosim): every FMU steps with the inputs of the last exchange, so the
  bearing outputs are one exchange behind: step n + 1 starts from X_n with the laws linearised
  at X_n-1.

The reference is ``gsb run``'s master (:func:`iterative`,
:class:`orchestrator.coupling.master.Master`: the same first pass as lag 0, then Newton on the
bearing laws until the force mismatch is below the case's tolerance).

The measure (:func:`orbit_error`): bearing 1's journal position (s, t) [m] of the scheme, x,
and of a reference, r, compared at the instants n dt, n = 0 .. N, where dt is the case's step
(every 2^k-th step of a run at dt / 2^k, so runs of every step cover the same physical time
N dt from the static start)::

    E = max_n max_{a in (s, t)} |x_a(n dt) - r_a(n dt)| / max_{a in (s, t)} ptp_a(r)

with ``ptp_a(r) = max_n r_a(n dt) - min_n r_a(n dt)``, the orbit's larger peak-to-peak
amplitude over the same instants; in percent. :func:`study` computes it at the steps dt,
dt/2, ... (the case with ``simulation.steps_per_mesh_period`` multiplied by 2^k, the step
``gsb run`` would take with that field) for each scheme against the iterative master at the
same step (the coupling error alone) and against the iterative master at dt (what a tool user
compares with ``gsb run`` of the case), and gives the iterative master's own difference to
itself at dt (the time discretisation, which bounds what a smaller step can buy).

The runs last 32 mesh periods by default: more than a pinion revolution (26 mesh periods of
the paper's case, the period of the unbalance at bearing 1), by when the orbit's peak-to-peak
and the differences have stopped growing (measured: the largest differences are reached
within 12 mesh periods and recur every revolution; 64 periods move the errors at the case's
own step by less than 0.2 of a percentage point, the detuned lag 1's by one).

Each step is measured a second time shortened by :data:`DETUNE` (1e-6 of it), both schemes and
their reference. At a step that divides the mesh period, a contact line entering or leaving
the path of contact at the start of every mesh period falls exactly on a step's end (the
structure ends that step on the event, :mod:`gear_fmu.structure`); the slightly shorter step
moves it just inside the next step. The iterative master and lag 0 hardly notice, but lag 1
at the paper's step does (from 24 % to 14 % of the orbit): there the figure depends on the last
digits of the step a tool is given, and the detuned columns show by how much.
"""

from __future__ import annotations

import argparse
import math
import shlex
import sys
import time

import numpy as np

__all__ = ["SCHEMES", "command_line", "iterative", "main", "non_iterative", "observed_order",
           "orbit_error", "study", "table"]

CASE = "baguet2010_spur"
#: lag of each non-iterative scheme (steps between the journal states the laws were
#: linearised at and the start of the step they serve) and the hosts that run it
SCHEMES = {0: "lag 0 (Gauss-Seidel: OMSimulator)", 1: "lag 1 (Jacobi: ecos, libcosim)"}
#: the journal compared (bearing 1, on the pinion shaft) and its axes (s, t)
BEARING = 0
#: relative shortening of the step of the second measurement at each step (module docstring)
DETUNE = 1e-6
#: default run length [mesh periods] and number of steps dt, dt/2, ... (module docstring)
PERIODS, LEVELS = 32, 4


def _started(case):
    """The case's in-process master after the static solution X0 and the end of
    initialisation (what ``gsb run`` does before the first step)."""
    from orchestrator.coupling.system import build_master

    master = build_master(case, in_process=True)
    master.solve_static()
    master.exit_initialization()
    return master


def non_iterative(case, steps: int, lag: int = 1, dt: float | None = None) -> np.ndarray:
    """(steps + 1, 4, 4) journal states [m, m/s] of a non-iterating master with the
    in-process physics: X0 from the static solution, then ``steps`` steps of ``dt`` [s]
    (default the case's ``time_step``), step n + 1 from X_n with the laws linearised at
    X_n-lag (lag 0: Gauss-Seidel; lag 1: Jacobi, as ecos runs the SSP; the first steps use
    X0's laws).

    Independent of :meth:`orchestrator.coupling.master.Master.step`: only the static solution
    is the master's, as an SSP carries it in its start values.
    """
    from bearing_fmu.affine import AffineLaws
    from fmu_src import description

    if lag not in (0, 1):
        raise ValueError(f"lag {lag!r}: 0 (Gauss-Seidel) or 1 (Jacobi)")
    master = _started(case)
    structure, bearings = master.structure, master.bearings
    dt = description.time_step(case) if dt is None else dt
    laws = [master.laws]
    states = [structure.journal_states().copy()]
    for k in range(steps):
        structure.set_bearing_laws(laws[max(len(laws) - 1 - lag, 0)])
        structure.do_step(k * dt, dt)
        x = structure.journal_states().copy()
        laws.append(AffineLaws.linearise(x, *bearings.evaluate(x)))
        states.append(x)
    return np.array(states)


def iterative(case, steps: int, dt: float | None = None) -> np.ndarray:
    """(steps + 1, 4, 4) journal states of ``gsb run``'s master (the runner's loop: step i
    from t = i dt, converged to the case's tolerance), X0 first; ``dt`` as in
    :func:`non_iterative`."""
    from fmu_src import description

    master = _started(case)
    dt = description.time_step(case) if dt is None else dt
    states = [master.structure.journal_states().copy()]
    for i in range(steps):
        states.append(master.step(i * dt, dt).states.copy())
    return np.array(states)


def orbit_error(x: np.ndarray, ref: np.ndarray) -> float:
    """E of the module docstring: bearing :data:`BEARING`'s largest position difference over
    the larger peak-to-peak amplitude of ``ref``; ``x`` and ``ref`` (n, 4, 4) at the same
    instants. A fraction (not percent)."""
    x, ref = np.asarray(x)[:, BEARING, :2], np.asarray(ref)[:, BEARING, :2]
    if x.shape != ref.shape:
        raise ValueError(f"trajectories of {x.shape[0]} and {ref.shape[0]} instants")
    return float(np.abs(x - ref).max() / np.ptp(ref, axis=0).max())


def study(case_name: str = CASE, periods: int = PERIODS, levels: int = LEVELS,
          detune: float = DETUNE, echo=None) -> dict:
    """The errors of :data:`SCHEMES` at the steps dt / 2^k, k = 0 .. levels - 1, over
    ``periods`` mesh periods; ``echo(text)`` is told of each level.

    Returns ``{"case", "periods", "dt", "steps_per_mesh_period", "detune", "rows",
    "orbit_ptp"}`` (the last: bearing 1's peak-to-peak along s and t at dt [m]); each
    row ``{"k", "dt", "steps", "same", "detuned", "case_step", "iterative"}``: ``same[lag]``
    the scheme against the iterative master at the same step, ``detuned[lag]`` the same with
    both at the step times (1 - detune) (None if detune is 0), ``case_step[lag]`` the scheme
    against the iterative master at dt, ``iterative`` the iterative master at this step
    against itself at dt (all fractions, :func:`orbit_error`).
    """
    from fmu_src import description
    from fmu_src.case import load_case

    if periods < 1 or levels < 1:
        raise ValueError(f"periods {periods!r} and levels {levels!r} must be >= 1")
    if not 0.0 <= detune < 1e-2:
        raise ValueError(f"detune {detune!r}: 0 (none) up to 1e-2")
    base = load_case(case_name)
    spm = base["simulation.steps_per_mesh_period"]
    n = periods * spm
    rows, coarse = [], None
    for k in range(levels):
        case = base.with_overrides({"simulation.steps_per_mesh_period": spm * 2**k})
        steps, stride = n * 2**k, 2**k
        t0 = time.perf_counter()
        ref = iterative(case, steps)[::stride]
        runs = {lag: non_iterative(case, steps, lag)[::stride] for lag in SCHEMES}
        detuned = None
        if detune:
            h = description.time_step(case) * (1.0 - detune)
            other = iterative(case, steps, h)
            detuned = {lag: orbit_error(non_iterative(case, steps, lag, h), other)
                       for lag in SCHEMES}
        if coarse is None:
            coarse = ref
        rows.append({"k": k, "dt": description.time_step(case), "steps": steps,
                     "same": {lag: orbit_error(x, ref) for lag, x in runs.items()},
                     "detuned": detuned,
                     "case_step": {lag: orbit_error(x, coarse) for lag, x in runs.items()},
                     "iterative": orbit_error(ref, coarse)})
        if echo is not None:
            name = "dt" if k == 0 else f"dt/{2**k}"
            echo(f"{name}: {steps} steps a run, {time.perf_counter() - t0:.1f} s")
    return {"case": case_name, "periods": periods, "dt": description.time_step(base),
            "steps_per_mesh_period": spm, "detune": detune, "rows": rows,
            "orbit_ptp": np.ptp(coarse[:, BEARING, :2], axis=0).tolist()}


def observed_order(rows: list, lag: int) -> float | None:
    """log2 of the ratio of the same-step errors of ``lag`` at the last two steps (the order
    p of E ~ dt^p); None with fewer than two rows or a zero error."""
    if len(rows) < 2:
        return None
    a, b = rows[-2]["same"][lag], rows[-1]["same"][lag]
    return math.log2(a / b) if a > 0.0 and b > 0.0 else None


def table(result: dict, command: str | None = None) -> str:
    """The markdown table of :func:`study`'s result (errors E in percent), with the command
    that printed it."""
    spm, detune = result["steps_per_mesh_period"], result["detune"]
    ptp_s, ptp_t = result["orbit_ptp"]
    head = ["step [s]", "steps / mesh period", "lag 0", "lag 1"]
    if detune:
        head += [f"lag 0, step x (1 - {detune:g})", f"lag 1, step x (1 - {detune:g})"]
    head += ["lag 0 vs iterative at dt", "lag 1 vs iterative at dt",
             "iterative vs iterative at dt"]
    lines = [
        f"Case `{result['case']}`, {result['periods']} mesh periods from the static start, "
        f"dt = T_mesh / {spm} = {result['dt']:.6g} s; bearing 1's orbit (iterative master at "
        f"dt): peak-to-peak {ptp_s:.2e} m along s, {ptp_t:.2e} m along t. E [%] = bearing "
        "1's largest journal position difference (s or t, at the instants n dt) / the "
        "reference orbit's larger peak-to-peak; columns \"lag 0\", \"lag 1\": against the "
        "iterative master at the same step.",
        "",
        "| " + " | ".join(head) + " |",
        "| " + " | ".join("---" for _ in head) + " |",
    ]
    for r in result["rows"]:
        name = "dt" if r["k"] == 0 else f"dt/{2**r['k']}"
        cells = [f"{name} = {r['dt']:.4g}", str(spm * 2**r["k"])]
        cells += [f"{100 * r['same'][lag]:.2f}" for lag in SCHEMES]
        if detune:
            cells += [f"{100 * r['detuned'][lag]:.2f}" for lag in SCHEMES]
        cells += [f"{100 * r['case_step'][lag]:.2f}" for lag in SCHEMES]
        cells.append(f"{100 * r['iterative']:.2f}")
        lines.append("| " + " | ".join(cells) + " |")
    orders = [(lag, observed_order(result["rows"], lag)) for lag in SCHEMES]
    if all(p is not None for _, p in orders):
        lines += ["", "Observed order p of the coupling error E ~ dt^p (same step, last "
                  "halving): " + ", ".join(f"lag {lag} {p:.2f}" for lag, p in orders) + "."]
    if command:
        lines += ["", f"Printed by `{command}`."]
    return "\n".join(lines)


def command_line(case: str = CASE, periods: int = PERIODS, levels: int = LEVELS,
                 detune: float = DETUNE) -> str:
    """The command that prints :func:`table` for these arguments (every one spelled out)."""
    return " ".join(["python -m orchestrator.studies.coupling_accuracy", shlex.quote(case),
                     f"--periods {periods}", f"--levels {levels}", f"--detune {detune:g}"])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m orchestrator.studies.coupling_accuracy",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("case", nargs="?", default=CASE, help=f"case (default {CASE})")
    parser.add_argument("--periods", type=int, default=PERIODS,
                        help=f"mesh periods from the static start (default {PERIODS})")
    parser.add_argument("--levels", type=int, default=LEVELS,
                        help=f"steps dt, dt/2, ... dt/2^(levels-1) (default {LEVELS})")
    parser.add_argument("--detune", type=float, default=DETUNE,
                        help=f"also run at each step times (1 - DETUNE) (default {DETUNE:g}; "
                        "0: not)")
    args = parser.parse_args(argv)
    if args.periods < 1:
        parser.error(f"--periods {args.periods}: at least 1")
    if not 1 <= args.levels <= 6:
        parser.error(f"--levels {args.levels}: 1 to 6 (each level doubles the steps)")
    if not 0.0 <= args.detune < 1e-2:
        parser.error(f"--detune {args.detune:g}: 0 up to 1e-2")
    from fmu_src.case import CaseError

    t0 = time.perf_counter()
    try:
        result = study(args.case, args.periods, args.levels, args.detune,
                       echo=lambda s: print(s, file=sys.stderr, flush=True))
    except CaseError as exc:
        parser.error(str(exc))
    print(table(result, command_line(args.case, args.periods, args.levels, args.detune)))
    print(f"all runs: {time.perf_counter() - t0:.0f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
