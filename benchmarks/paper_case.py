"""Wall time of the paper's spur case (Table 4): 2048 mesh periods, 65,536 steps.

Usage: ``python benchmarks/paper_case.py [--periods N] [--skip-fmu] [--contact-location]
[--threads N] [--breakdown] [--case NAME]``

``--case NAME`` times another shipped case the same way (``two_stage_reducer``: its periods are
those of its fastest mesh), and also with its bearings as the case gives them ("as given").

Runs, in one process and in this order: hybrid bearings in-process, the linear 8-coefficient
model in-process (Table 4 case 0), hybrid through the FMUs (fmpy), and prints wall time,
steps/s, bearing evaluations (= Reynolds solves for the film models), coupled iterations per
step, and the ratios. ``--contact-location`` adds hybrid in-process runs of the spur and
helical cases with ``simulation.locate_contact`` off (the steps not cut at the contact events,
:mod:`gear_fmu.structure`) and the ratio of the default (on) to them. ``--threads N`` adds the
hybrid in-process run with its bearings on N threads (``gsb run --threads``) and the ratio of
the run on one thread to it. The numba kernels are
compiled before the clock starts (a 2-period warm-up run per configuration). The paper needed
8 minutes for case 2 in 2010.

``--breakdown`` times, per coupled iteration (microseconds), the compiled coupled steps
(:func:`orchestrator.coupling.step.coupled_steps`, one call per block of steps: the structure,
the bearings and the master's update, the same iteration in-process and through the FMUs), the
structure's plan of each block, the static solution's calls and the results writer, and the
rest (the runner's loop, the progress test); the timers add about 0.5 us per call. Through the
FMUs the gear-shaft FMU's doStep and its state's save and restore run its slave's Python inside
the compiled call; the bearing FMUs' native layer calls the hybrid law without Python
(``fmu_src/native/patches/0011-native-bearing-law.patch``).
"""

from __future__ import annotations

import argparse
import contextlib
import platform
import tempfile
import time

from fmu_src.case import load_case
from orchestrator.run.runner import run_case

CASE = "baguet2010_spur"


INPROCESS = "orchestrator.coupling.inprocess.InProcessStructure"
FMU_STRUCTURE = "orchestrator.coupling.fmi.structure.FmuStructure"
#: (label, class path, method) of the calls timed by --breakdown
TIMED = [
    ("compiled coupled steps", "orchestrator.coupling.step", "coupled_steps"),
    ("structure: plan of a block", INPROCESS, "compiled_block"),
    ("structure: plan of a block", FMU_STRUCTURE, "compiled_block"),
    ("bearing groups", "orchestrator.coupling.inprocess.ModelBearings", "compiled_groups"),
    ("bearing groups", "orchestrator.coupling.fmi.bearings.FmuBearings", "compiled_groups"),
    ("static solution", "orchestrator.coupling.master.Master", "solve_static"),
    ("outputs + results writer", "orchestrator.run.results.ResultsWriter", "append"),
    ("outputs + results writer", "orchestrator.run.results.ResultsWriter", "append_rows"),
]


@contextlib.contextmanager
def timed_calls(targets=TIMED, counts: dict | None = None):
    """Wrap the callables of ``targets`` ((label, path, name), :data:`TIMED` by default; the
    path names a class, whose method ``name`` is wrapped, or a module, whose function is)
    with timers; yields ``{label: seconds}``, and counts the calls per label in ``counts``.
    Through FMUs the slaves' calls are timed too: pythonfmu runs them in this interpreter."""
    import importlib

    totals: dict[str, float] = {}
    saved = []
    for label, path, name in targets:
        try:
            owner = importlib.import_module(path)
        except ModuleNotFoundError:  # "module.Class"
            module, cls_name = path.rsplit(".", 1)
            try:
                owner = getattr(importlib.import_module(module), cls_name)
            except ModuleNotFoundError:  # a module this commit does not have
                owner = None
        raw = owner.__dict__.get(name) if owner is not None else None
        if raw is None:  # a kernel this commit does not have (the benchmark runs on older ones)
            continue
        func = raw.__func__ if isinstance(raw, classmethod) else raw

        def wrapper(*a, _f=func, _label=label, **kw):
            t0 = time.perf_counter()
            try:
                return _f(*a, **kw)
            finally:
                totals[_label] = totals.get(_label, 0.0) + time.perf_counter() - t0
                if counts is not None:
                    counts[_label] = counts.get(_label, 0) + 1

        setattr(owner, name, classmethod(wrapper) if isinstance(raw, classmethod) else wrapper)
        saved.append((owner, name, raw))
    try:
        yield totals
    finally:
        for owner, name, raw in reversed(saved):
            setattr(owner, name, raw)


def breakdown(periods: int, in_process: bool, name: str = CASE) -> None:
    """Per coupled iteration: the timed calls (:data:`TIMED`) and the rest."""
    kw = dict(in_process=in_process, progress=False)
    case = load_case(name, {"bearings.*.model": "hybrid"})
    with tempfile.TemporaryDirectory() as tmp:
        run_case(case.with_overrides({"simulation.mesh_periods": 2}), out_dir=tmp + "/w",
                 **kw)  # warm-up
        plain = run_case(case.with_overrides({"simulation.mesh_periods": periods}),
                         out_dir=tmp + "/p", **kw)
        with timed_calls() as totals:
            s = run_case(case.with_overrides({"simulation.mesh_periods": periods}),
                         out_dir=tmp + "/t", **kw)
    n = s.iterations
    us = 1e6 / n
    where = "in-process" if in_process else "FMUs (fmpy)"
    print(f"\nbreakdown, hybrid {where}: {s.steps} steps, {n} coupled iterations "
          f"({s.iterations_per_step:.2f} per step); {s.wall_time:.2f} s timed, "
          f"{plain.wall_time:.2f} s without the timers")
    for label, total in sorted(totals.items(), key=lambda kv: -kv[1]):
        print(f"  {label:30s} {total * us:8.1f} us/iteration  {100 * total / s.wall_time:5.1f} %")
    rest = s.wall_time - sum(totals.values())
    print(f"  {'rest (loop, progress, ...)':30s} {rest * us:8.1f} us/iteration  "
          f"{100 * rest / s.wall_time:5.1f} %")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--periods", type=int, default=2048)
    parser.add_argument("--case", default=CASE,
                        help="another shipped case (e.g. two_stage_reducer): its own bearing "
                             "models are timed too ('as given')")
    parser.add_argument("--skip-fmu", action="store_true")
    parser.add_argument("--contact-location", action="store_true",
                        help="also time the runs with simulation.locate_contact off")
    parser.add_argument("--threads", type=int, default=1,
                        help="also time the hybrid in-process run on this many threads")
    parser.add_argument("--breakdown", action="store_true",
                        help="only the per-iteration breakdown (hybrid, in-process and FMUs)")
    args = parser.parse_args()
    steps = args.periods * load_case(args.case)["simulation.steps_per_mesh_period"]
    if args.breakdown:
        print(f"machine: {platform.machine()}, CPython {platform.python_version()}; "
              f"{args.case}, {args.periods} mesh periods ({steps} steps)")
        breakdown(args.periods, True, args.case)
        if not args.skip_fmu:
            breakdown(args.periods, False, args.case)
        return
    configs = [("hybrid", True), ("linear", True)]
    if args.case != CASE:
        configs.append(("as given", True))
    if not args.skip_fmu:
        configs.append(("hybrid", False))
    if args.threads > 1:
        configs.append(("hybrid", True, "threads"))
    if args.contact_location:
        configs += [("hybrid", True, "no-location"), ("hybrid", True, "helical"),
                    ("hybrid", True, "helical-no-location")]
    print(f"machine: {platform.machine()}, CPython {platform.python_version()}; {args.case}, "
          f"{args.periods} mesh periods of the fastest mesh ({steps} steps)")
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        for model, in_process, *variant in configs:
            kw = dict(in_process=in_process, out_dir=tmp, progress=False)
            name = variant[0] if variant else ""
            if name == "threads":  # the same results file name: another folder
                kw |= dict(threads=args.threads, out_dir=f"{tmp}/threads")
                name = f"{args.threads} threads"
            overrides = {"simulation.locate_contact": "no-location" not in name}
            if model != "as given":
                overrides["bearings.*.model"] = model
            run = load_case("baguet2010_helical" if "helical" in name else args.case, overrides)
            run_case(run.with_overrides({"simulation.mesh_periods": 2}),
                     **kw)  # warm-up: numba, FMU extraction
            s = run_case(run.with_overrides({"simulation.mesh_periods": args.periods}), **kw)
            label = f"{model:7s} {'in-process' if in_process else 'FMUs (fmpy)'} {name}"
            rows[(model, in_process, *variant)] = s
            solves = len(run.names("bearings")) * s.bearing_evaluations
            print(f"{label:28s} {s.wall_time:7.1f} s  {s.steps_per_second:7.0f} steps/s  "
                  f"{s.iterations_per_step:5.2f} it/step  {solves:9d} bearing evaluations  "
                  f"static {s.static_time * 1e3:.0f} ms")
    ref = rows[("hybrid", True)].wall_time
    print(f"linear / hybrid (in-process): {rows[('linear', True)].wall_time / ref:.2f}")
    if ("hybrid", False) in rows:
        print(f"FMU / in-process (hybrid): {rows[('hybrid', False)].wall_time / ref:.2f}")
    if ("hybrid", True, "threads") in rows:
        print(f"hybrid in-process, 1 / {args.threads} threads: "
              f"{ref / rows[('hybrid', True, 'threads')].wall_time:.2f}")
    if args.contact_location:
        off = rows[("hybrid", True, "no-location")].wall_time
        print(f"spur: contact location on / off: {ref / off:.3f}")
        h_on = rows[("hybrid", True, "helical")].wall_time
        h_off = rows[("hybrid", True, "helical-no-location")].wall_time
        print(f"helical: contact location on / off: {h_on / h_off:.3f}")


if __name__ == "__main__":
    main()
