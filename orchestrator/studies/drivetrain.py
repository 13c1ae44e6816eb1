"""``docs/drivetrain.md``: how the drivetrain, the damping model and the time step move the
paper's spur case, generated (no number typed by hand).

    python -m orchestrator.studies.drivetrain --out docs/drivetrain.md [--periods 512]
    python -m orchestrator.studies.drivetrain --render results.json --out docs/drivetrain.md

Every configuration of :data:`PLAN` is a full in-process run of the shipped case
``baguet2010_spur`` (hybrid bearings) with some case fields overridden, on a Dask LocalCluster
(two single-threaded workers; ``--scheduler`` for another one). Each run is reduced to the
report of ``gsb run`` (:func:`orchestrator.analysis.metrics.run_report`: R, the bearing-force
peak-to-peak and the lines of the bearing-1 force norm over the last gear revolution), and the
linearised system of each configuration (:func:`orchestrator.analysis.campbell.linearise`) gives the
damped mesh modes that explain it. The page also carries the models' own documentation
(the module docstrings of :mod:`gear_fmu.drivetrain` and :mod:`gear_fmu.modal.damping`, with the
formula of each damping model) and states the plan it was generated from (:func:`plan_text`);
``tests/orchestrator/studies/test_drivetrain_study.py`` checks that both still match the code.
The raw results are saved beside the page (``<page>.json``) so that ``--render`` redraws it
without the runs.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

__all__ = ["MOTOR_CASE", "PLAN", "main", "plan_text", "render", "run_plan"]

CASE = "baguet2010_spur"
#: the shipped case with a motor (compared with the paper at the end of the page)
MOTOR_CASE = "baguet2010_spur_motor"
_OFF = {"simulation.consistent_start": False, "simulation.locate_contact": False}

#: (group, label, case, overrides): the configurations of the study
PLAN = (
    ("input", "free input end, clamped output (the paper's case)", CASE, {}),
    ("input", "motor 0.05 kg m^2, rigid", CASE, {"drive.motor_inertia": 0.05}),
    ("input", "motor 0.5 kg m^2, rigid", CASE, {"drive.motor_inertia": 0.5}),
    ("input", "motor 0.5 kg m^2 behind a coupling (1e4 N m/rad, 5 N m s/rad)", CASE,
     {"drive.motor_inertia": 0.5, "drive.motor_coupling_stiffness": 1e4,
      "drive.motor_coupling_damping": 5.0}),
    ("output", "load 5 kg m^2 on the output end, rigid (output_end = load)", CASE,
     {"drive.output_end": "load", "drive.load_inertia": 5.0}),
    ("output", "load 5 kg m^2 behind a coupling (1e5 N m/rad)", CASE,
     {"drive.output_end": "load", "drive.load_inertia": 5.0,
      "drive.load_coupling_stiffness": 1e5}),
    ("damping", "modal 0.03 on the structure's modes (basis = structure)", CASE,
     {"simulation.damping_basis": "structure"}),
    ("damping", "Rayleigh, 0.03 at 1000 Hz and 5000 Hz", CASE,
     {"simulation.damping_model": "rayleigh", "simulation.rayleigh_frequencies": [1e3, 5e3]}),
    ("damping", "modal 0.03 and a mesh damping ratio 0.05", CASE,
     {"simulation.mesh_damping_ratio": 0.05}),
    ("damping", "no structural damping (modal 0)", CASE, {"simulation.damping_ratio": 0.0}),
    ("time step", "T_mesh / 64", CASE, {"simulation.steps_per_mesh_period": 64}),
    ("time step", "T_mesh / 128", CASE, {"simulation.steps_per_mesh_period": 128}),
    ("time step", "T_mesh / 32 without the time-integration refinements (zero start "
     "acceleration, contact changes inside steps)", CASE, _OFF),
    ("time step", "T_mesh / 128 without the refinements", CASE,
     {"simulation.steps_per_mesh_period": 128, **_OFF}),
    ("motor case", "the shipped case baguet2010_spur_motor", MOTOR_CASE, {}),
)

GROUPS = {
    "input": "Input end (motor)",
    "output": "Output end (load)",
    "damping": "Damping model",
    "time step": "Time step and time integration",
    "motor case": "The paper's case with a motor",
}


def plan_text(periods: int) -> str:
    """The plan as a stable text (written into the page; the test compares it)."""
    return "\n".join(f"{g} | {label} | {case} | {sorted(o.items())!r}"
                     for g, label, case, o in PLAN) + f"\nperiods = {periods}"


def run_point(case_name: str, overrides: dict, periods: int) -> dict:
    """One configuration (on a worker): the run's report and the damped mesh modes."""
    from fmu_src.case import load_case
    from orchestrator.analysis.campbell import linearise
    from orchestrator.run.runner import simulate_case
    from orchestrator.run.spec import RunSpec

    case = load_case(case_name, {**overrides, "simulation.mesh_periods": periods})
    t0 = time.perf_counter()
    summary = simulate_case(RunSpec.of(case, in_process=True), echo_warnings=False).summary
    wall = time.perf_counter() - t0
    lin = linearise(case, undamped=False)
    d = lin.damped
    mesh = [(float(f), float(z), float(e)) for f, z, e in zip(
        d.frequency_hz, d.damping_ratio, d.mesh_energy_fraction, strict=True)
        if not math.isnan(e) and e >= 0.25 and f > 0.0]
    cb = np.array([lin.cb[j][1, 1] for j in range(4)])
    r = summary.report
    # the page names the lines by bearing 1's (pinion) orders: 1x, gear_1x, 26x, 52x, 78x
    labels = ["1x" if q == 1.0 else f"{q:.0f}x" if label.endswith("GMF") else "gear_1x"
              for label, q in zip(r["line_labels"], r["line_orders"][0], strict=True)]
    return {"R": float(r["dynamic_factor"][0]),
            "ptp": np.asarray(r["bearing_force_ptp"]).tolist(),
            "lines": np.asarray(r["line_amplitudes"]).tolist(),
            "labels": labels, "mesh_modes": mesh,
            "cb_tt": cb.tolist(), "wall_s": wall, "steps": summary.steps,
            "iterations_per_step": summary.iterations_per_step}


def run_plan(periods: int, scheduler: str | None = None, workers: int = 2,
             progress: bool = True) -> list[dict]:
    """Every configuration of :data:`PLAN` (Dask), in the plan's order."""
    from dask.distributed import as_completed

    from orchestrator.sweeps.runner import dask_client

    client, cluster = dask_client(scheduler, workers, 60.0)
    try:
        futures = {client.submit(run_point, case, overrides, periods, pure=False): i
                   for i, (_, _, case, overrides) in enumerate(PLAN)}
        out: list = [None] * len(PLAN)
        t0 = time.perf_counter()
        for done, fut in enumerate(as_completed(futures), 1):
            i = futures[fut]
            out[i] = fut.result()
            if progress:
                print(f"[{done}/{len(PLAN)}] {time.perf_counter() - t0:6.0f} s  "
                      f"{PLAN[i][1]}: R = {out[i]['R']:.3f}", flush=True)
        return out
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _line(res: dict, label: str) -> float:
    return res["lines"][0][res["labels"].index(label)]


def render(results: list[dict], periods: int, wall_s: float) -> str:
    """The page (module docstring) from the results of :func:`run_plan`."""
    labels = results[0]["labels"]
    show = [x for x in labels if x != "gear_1x"]
    head = ("| configuration | R | bearing 1 ptp [N] | bearing 3 ptp [N] | "
            + " | ".join(f"bearing 1 {x} [N]" for x in show)
            + " | damped mesh modes [Hz] (ratio) |")
    rule = "|" + " --- |" * (5 + len(show))
    lines = [
        "<!-- Generated by `python -m orchestrator.studies.drivetrain --out docs/drivetrain.md "
        f"--periods {periods}`; do not edit by hand. -->",
        "# Drivetrain, damping and time step: what moves the paper's spur case",
        "",
        f"Each row is a run of the spur case (220 N m, 325 rad/s, e_mu 0.6 mm, hybrid bearings, "
        f"{periods} mesh periods, in-process) with the fields of its configuration changed; "
        "the figures are those `gsb run` reports over the last gear revolution: the dynamic "
        "factor R (maximum over static mesh load), the peak-to-peak of the bearing force norm, "
        "and the amplitudes of the lines of the bearing-1 force norm at pinion orders "
        f"({', '.join(show)}). The last column lists the damped modes of the linearised system "
        "(`gsb modal`) that store at least 25 % of their strain energy in the mesh: the "
        "response follows them, not the undamped mesh mode. Generated in "
        f"{wall_s / 60:.0f} minutes on 2 cores.",
        "",
    ]
    lines += model_docs()
    for group, title in GROUPS.items():
        lines += [f"## {title}", "", head, rule]
        for (g, label, _, _), res in zip(PLAN, results, strict=True):
            if g != group:
                continue
            modes = ", ".join(f"{f:.0f} ({z:.3f})" for f, z, _ in res["mesh_modes"])
            lines.append(
                f"| {label} | {res['R']:.3f} | {res['ptp'][0]:.0f} | {res['ptp'][2]:.0f} | "
                + " | ".join(f"{_line(res, x):.0f}" for x in show) + f" | {modes} |")
        lines.append("")
    lines += _findings(results)
    lines += ["## Plan", "", "```", plan_text(periods), "```", ""]
    return "\n".join(lines)


def model_docs() -> list[str]:
    """The drivetrain and damping models as their modules document them (one source)."""
    import gear_fmu.drivetrain
    import gear_fmu.modal.damping

    out = ["## The models", ""]
    for mod in (gear_fmu.drivetrain, gear_fmu.modal.damping):
        out += [f"From `{mod.__name__}`:", "", "```text", mod.__doc__.strip(), "```", ""]
    return out


def _by_label(results, text):
    for (_, label, _, _), res in zip(PLAN, results, strict=True):
        if label.startswith(text):
            return res
    raise KeyError(text)


def _findings(results: list[dict]) -> list[str]:
    """Sentences computed from the results (what the tables say)."""
    base = _by_label(results, "free input end")
    m05 = _by_label(results, "motor 0.05")
    m5 = _by_label(results, "motor 0.5 kg m^2, rigid")
    coupled = _by_label(results, "motor 0.5 kg m^2 behind")
    load = _by_label(results, "load 5 kg m^2 on the output end")
    t128 = _by_label(results, "T_mesh / 128")
    off = _by_label(results, "T_mesh / 32 without")
    motor = _by_label(results, "the shipped case")
    cb = base["cb_tt"]
    big = max(("26x", "52x", "78x"), key=lambda x: _line(motor, x))
    one_x, mesh_big = _line(motor, "1x"), _line(motor, big)
    return [
        "## What the tables say",
        "",
        f"- A motor inertia on the input end moves the case most: R {base['R']:.2f} free, "
        f"{m05['R']:.2f} with 0.05 kg m^2, {m5['R']:.2f} with 0.5 kg m^2; bearing-1 "
        f"peak-to-peak {base['ptp'][0]:.0f} N, {m05['ptp'][0]:.0f} N, {m5['ptp'][0]:.0f} N. "
        "A free input end lets the pinion's torsion join the mesh modes; the motor's inertia "
        "holds it (the damped mesh modes move, last column). Behind a soft coupling the same "
        f"motor is isolated at the mesh frequencies: R {coupled['R']:.2f}, peak-to-peak "
        f"{coupled['ptp'][0]:.0f} N, as with no motor.",
        f"- The output condition barely matters: a 5 kg m^2 load instead of the clamp gives R "
        f"{load['R']:.3f} against {base['R']:.3f} (the gear's 4.5 kg m^2 already holds the "
        "output end).",
        "- The mesh-order lines of the bearing forces come from the film damping acting on "
        "sub-micrometre journal motion: the direct film damping Cb_tt at X0 is "
        + ", ".join(f"{c:.3g}" for c in cb) + " N s/m at bearings 1-4.",
        f"- The time step: at T/32 the 78x line is {_line(base, '78x'):.0f} N against "
        f"{_line(t128, '78x'):.0f} N at T/128, R {base['R']:.3f} against {t128['R']:.3f}. "
        f"Without the refinements (zero start acceleration, contact changes inside steps) T/32 "
        f"gives R {off['R']:.3f} and a 78x line of {_line(off, '78x'):.0f} N.",
        f"- With a motor (shipped case `{MOTOR_CASE}`): R {motor['R']:.2f}, bearing-1 "
        f"peak-to-peak {motor['ptp'][0]:.0f} N; the 1x (unbalance) line is {one_x:.0f} N and "
        f"the largest mesh line ({big}) {mesh_big:.0f} N. The paper finds the bearing forces "
        "dominated by the unbalance; "
        + ("so does this case." if one_x >= mesh_big else
           f"here the mesh line is still {mesh_big / max(one_x, 1e-9):.1f} times the 1x line, "
           "so the departure is reduced, not removed: the paper's drivetrain, damping and "
           "tooth stiffness are not stated, and each moves these lines."),
        "",
    ]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m orchestrator.studies.drivetrain",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="docs/drivetrain.md", help="page to write")
    parser.add_argument("--periods", type=int, default=512, help="mesh periods per run")
    parser.add_argument("--scheduler", default=None, help="Dask scheduler address")
    parser.add_argument("--workers", type=int, default=2, help="LocalCluster workers")
    parser.add_argument("--render", default=None, metavar="JSON",
                        help="only redraw the page from the results saved by a run")
    args = parser.parse_args(argv)
    out = Path(args.out)
    if args.render:
        saved = json.loads(Path(args.render).read_text())
        if saved["plan"] != plan_text(saved["periods"]):
            parser.error(f"{args.render} was computed for another plan: run the study again")
        out.write_text(render(saved["results"], saved["periods"], saved["wall_s"]))
        print(f"wrote {out}")
        return 0
    if args.periods < 64:
        parser.error(f"--periods {args.periods}: at least 64 (a gear revolution is 157)")
    t0 = time.perf_counter()
    results = run_plan(args.periods, args.scheduler, args.workers)
    wall = time.perf_counter() - t0
    saved = out.with_suffix(".json")
    saved.write_text(json.dumps({"plan": plan_text(args.periods), "periods": args.periods,
                                 "wall_s": wall, "results": results}))
    out.write_text(render(results, args.periods, wall))
    print(f"wrote {out} (results: {saved})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
