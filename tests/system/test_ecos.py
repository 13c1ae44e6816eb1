"""ecos (ecospy 0.7.2, a C++ co-simulation master) runs the SSP archive of ``gsb export-ssp``.

ecos is non-iterative and of Jacobi type: each step, every FMU steps with the inputs of the
last exchange, then all outputs are exchanged. The bearing FMUs' outputs exchanged after step
n were evaluated at the journal states of step n - 1, so the gear FMU steps from X_n with the
bearing laws linearised at X_{n-1} (it knows where: the ``*_eval`` inputs).
:func:`orchestrator.studies.coupling_accuracy.non_iterative` emulates that scheme with the
in-process physics, independently of ecos and of this package's master (the coupling-accuracy
study runs it, and its lag-0 variant, at several steps): ecos gives its trajectories to
round-off, i.e. it runs the FMUs as docs/fmu-variables.md describes. The difference to
``gsb run`` (iterative, converged to the case's tolerance every step) is the non-iterative
coupling error at the paper's step; printed.

Two hosts: ecospy's library in a Python process (values read at full precision), and the
``ecos`` command (a C++ process without Python: the FMUs' loader loads libpython), whose exit
is checked over many runs. Skipped where ecos cannot run (ecospy not installed; ecos needs
libtbb: ``pip install ecospy tbb``).
"""

from __future__ import annotations

import csv
import importlib.util
import json
import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.helpers import film_bounds, probe_command, probe_env

_SPEC = importlib.util.find_spec("ecospy")  # not imported here: it needs libtbb at import
if _SPEC is None:
    pytest.skip("ecospy is not installed (pip install ecospy tbb)", allow_module_level=True)
ECOSPY = Path(next(iter(_SPEC.submodule_search_locations)))

CASE = "baguet2010_spur"
STEPS = 64


def _env() -> dict:
    """ecos's binaries need libtbb (the tbb wheel puts it in <prefix>/lib); nothing else."""
    lib = str(Path(sys.prefix) / "lib")
    return dict(os.environ, LD_LIBRARY_PATH=os.pathsep.join(
        p for p in (lib, os.environ.get("LD_LIBRARY_PATH", "")) if p))


@pytest.fixture(scope="module")
def ecos_cli(tmp_path_factory):
    """The ecos command, copied out of the wheel with its exec bit (pip drops it)."""
    src = ECOSPY / "binaries" / "ecos"
    if not src.is_file():
        pytest.skip(f"ecospy has no ecos binary for this platform ({src})")
    exe = tmp_path_factory.mktemp("ecos") / "ecos"
    shutil.copy2(src, exe)
    exe.chmod(exe.stat().st_mode | stat.S_IXUSR)
    proc = subprocess.run([str(exe), "--help"], capture_output=True, text=True, env=_env())
    if proc.returncode != 0:
        pytest.skip(f"ecos cannot run here: {proc.stderr.strip()[-300:]}")
    return exe


def _dt() -> float:
    from fmu_src import description
    from fmu_src.case import load_case

    return description.time_step(load_case(CASE))


@pytest.fixture(scope="module")
def ecos_python(ssp_file):
    """ecospy (ecos's library in a Python process): the 16 journal outputs after the
    initialisation and after each of STEPS steps, at full precision."""
    cmd = probe_command("tests.probes.ecos", "simulate",
                        {"ssp": ssp_file, "step_size": _dt(), "steps": STEPS})
    # faulthandler: a crash of the host (an exit-time SIGSEGV was seen, intermittently, in
    # full-suite runs) leaves its stacks in the message below
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600,
                          env=dict(probe_env(_env()), PYTHONFAULTHANDLER="1"),
                          cwd=ssp_file.parent)
    if proc.returncode != 0 and "libtbb" in proc.stderr:
        pytest.skip(f"ecos cannot run here: {proc.stderr.strip()[-300:]}")
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    return np.array(out["x"]).reshape(-1, 4, 4), np.array(out["e"])


def test_ecos_runs_the_ssp_as_a_jacobi_master_would(ecos_python):
    """ecos's trajectories equal the emulated Jacobi scheme's to the film solver's accuracy
    over 64 steps, not to the bit: the hybrid film solver starts from its last solution (its
    force within tol = 1e-8 of the exact one, whatever the start), and ecos calls the bearing
    FMUs in its own sequence. The bounds are that argument's, not a measurement's
    (:func:`tests.helpers.film_bounds`: positions 1e-8, velocities 7.7e-6 relative): measured
    here X0 3.4e-12, positions 3.7e-12 and velocities 9.5e-11; the coupling schemes differ
    by 1e-1 (tests/system/test_omsimulator.py)."""
    from fmu_src.case import load_case
    from orchestrator.studies.coupling_accuracy import non_iterative

    x, _ = ecos_python
    ref = non_iterative(load_case(CASE), STEPS, lag=1)
    scale = np.abs(ref[:, :, :2]).max()
    position = float(np.abs(x[:, :, :2] - ref[:, :, :2]).max() / scale)
    velocity = float(np.abs(x[:, :, 2:] - ref[:, :, 2:]).max() / np.abs(ref[:, :, 2:]).max())
    print(f"\necos vs the emulated Jacobi master, {STEPS} steps: positions {position:.1e}, "
          f"velocities {velocity:.1e}")
    bound, v_bound = film_bounds(scale, np.abs(ref[:, :, 2:]).max(), _dt())
    assert float(np.abs(x[0, :, :2] - ref[0, :, :2]).max() / scale) < bound  # the same X0
    assert position < bound and velocity < v_bound


def test_the_non_iterative_coupling_error_at_the_papers_step(ecos_python, tmp_path):
    """ecos vs ``gsb run`` (iterative, through the same FMUs) over 64 steps: the difference is
    the explicit coupling's; measured 0.75 % of the largest journal displacement at step 64
    (asserted below 1.2 %), after agreeing to the film solver's accuracy at step 1 (3.4e-12,
    asserted below 1e-11: test above)."""
    from fmu_src.case import load_case
    from orchestrator.run.results import read_results
    from orchestrator.run.runner import run_case

    x, _ = ecos_python
    s = run_case(load_case(CASE), steps=STEPS, in_process=True, out_dir=tmp_path,
                 progress=False)
    pos = read_results(s.results)["journal_position"]
    scale = np.abs(pos).max()
    diff = np.abs(x[1:, :, :2] - pos).max(axis=(1, 2)) / scale
    orbit = np.ptp(pos, axis=0).max()
    print(f"\necos (non-iterative) vs gsb run (iterative): largest journal difference "
          f"{diff[0]:.1e} after step 1, {diff[-1]:.2e} after step {STEPS} (relative to the "
          f"largest displacement; {np.abs(x[-1, :, :2] - pos[-1]).max() / orbit:.1%} of the "
          f"orbit's peak-to-peak {orbit:.2e} m)")
    assert diff[0] < 1e-11
    assert diff[-1] < 1.2e-2


def _cli_run(exe: Path, ssp: Path, folder: Path, steps: int):
    """The ecos command on an SSP (its parameter set ``case``) or an FMU."""
    folder.mkdir(parents=True, exist_ok=True)
    # ecos 0.7.2's command divides by zero (SIGFPE) below 10 steps (its progress display)
    pset = ["--parameterSet", "case"] if ssp.suffix == ".ssp" else []
    proc = subprocess.run([str(exe), "simulate", "--path", str(ssp), *pset,
                           "--stepSize", repr(_dt()), "--stopTime", repr(steps * _dt())],
                          capture_output=True, text=True, timeout=600, env=_env(), cwd=folder)
    rows = []
    path = folder / f"{ssp.stem}.csv"
    if path.is_file():
        with open(path) as fh:
            rows = [[c.strip() for c in r] for r in csv.reader(fh)]
    return proc, rows


@pytest.mark.parametrize("runs", [pytest.param(8, id="8-runs"),
                                  pytest.param(50, id="50-runs", marks=pytest.mark.slow)])
def test_the_ecos_command_runs_the_fmus_and_exits_cleanly(ecos_cli, ssp_file, ecos_python,
                                                          tmp_path, runs):
    """The ecos command (a C++ host, no Python in the process until the FMUs' loader loads
    it): every run exits with 0, nothing on stderr about an abort, and its CSV (6 decimals)
    shows the eccentricities the Python-hosted run computed."""
    _, ecc = ecos_python
    failures = []
    for k in range(runs):
        proc, rows = _cli_run(ecos_cli, ssp_file, tmp_path / f"r{k}", 20)
        bad = [w for w in ("corrupted", "Aborted", "Segmentation", "fatal", "[error]")
               if w in proc.stdout + proc.stderr]
        if proc.returncode != 0 or bad or len(rows) != 22:
            failures.append((k, proc.returncode, bad, len(rows), proc.stderr[-500:]))
            continue
        header = rows[0]
        for j in range(4):
            col = header.index(f"bearing{j + 1}::eccentricity[REAL]")
            shown = [r[col] for r in rows[1:]]
            assert shown == [f"{v:f}" for v in ecc[:21, j]], (k, j)
    print(f"\necos command: {runs - len(failures)} of {runs} runs exited cleanly")
    assert not failures, failures


def test_the_ecos_command_runs_the_transmission_fmu_as_gsb_run(ecos_cli, transmission_fmu,
                                                               tmp_path):
    """ecos's command (a C++ process, Python only inside the FMU) runs the transmission FMU
    at the case's step: each of 3 runs exits with 0, and the film forces and the mesh force
    of its CSV (6 decimals: 1e-6 N on forces of 100 to 3000 N) are gsb run's, rounded."""
    from fmu_src.case import load_case
    from tests.probes.transmission import OUTPUTS
    from tests.system.test_transmission_fmu import gsb_run_rows

    steps = 32
    ref = gsb_run_rows(load_case(CASE), steps)
    forces = [k for k, n in enumerate(OUTPUTS) if n.startswith("F_") or n == "mesh_force"]
    for k in range(3):
        proc, rows = _cli_run(ecos_cli, transmission_fmu, tmp_path / f"r{k}", steps)
        assert proc.returncode == 0, proc.stderr[-2000:]
        header = rows[0]
        got = np.array([[float(r[header.index(f"instance::{OUTPUTS[i]}[REAL]")])
                         for i in forces] for r in rows[2:]])
        assert got.shape == (steps, len(forces))
        assert np.abs(got - ref[:, forces]).max() <= 0.5e-6 * (1 + 1e-9), k


# --- another gear train: the two-stage reducer, every bearing model -------------------------
TRAIN_STEPS = 16


@pytest.fixture(scope="module")
def train_ssp(tmp_path_factory):
    """The SSP archive of the two-stage reducer (three shafts, two meshes, six bearings) with
    every registered bearing model (:data:`tests.orchestrator.coupling.test_fmu_steps.MIXED`):
    its own gear-shaft FMU, one component per bearing named after it, each of its model's
    FMU, the static solution X0 as start values; and the case."""
    from fmu_src.build.ssp import write_ssp
    from fmu_src.case import load_case
    from orchestrator.coupling.system import build_master
    from tests.conftest import TRAIN_CASE
    from tests.orchestrator.coupling.test_fmu_steps import MIXED

    case = load_case(TRAIN_CASE, MIXED)
    master = build_master(case, in_process=True)
    try:
        master.solve_static()
        laws = master.laws
    finally:
        master.close()
    return write_ssp(case, tmp_path_factory.mktemp("train_ssp"), laws=laws), case


@pytest.fixture(scope="module")
def train_ecos(train_ssp):
    """ecospy on the two-stage archive: the journal outputs (steps + 1, 6, 4) and the
    eccentricities (steps + 1, 6)."""
    from fmu_src import description
    from tests.conftest import TRAIN_CASE

    ssp, case = train_ssp
    cmd = probe_command("tests.probes.ecos", "simulate", {
        "ssp": ssp, "step_size": description.time_step(case), "steps": TRAIN_STEPS,
        "case": TRAIN_CASE})
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=900,
                          env=dict(probe_env(_env()), PYTHONFAULTHANDLER="1"), cwd=ssp.parent)
    if proc.returncode != 0 and "libtbb" in proc.stderr:
        pytest.skip(f"ecos cannot run here: {proc.stderr.strip()[-300:]}")
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    return np.array(out["x"]).reshape(TRAIN_STEPS + 1, 6, 4), np.array(out["e"])


def test_the_ssp_of_another_train_holds_a_component_per_bearing_of_its_model(train_ssp):
    """Six bearing components named after their bearings, each an instance of its own
    model's FMU (every model's once in the archive), wired to the train's gear-shaft FMU by
    the contract's connections."""
    import zipfile
    from xml.etree import ElementTree as ET

    from fmu_src.build.ssp import NS
    from fmu_src.contract import bearing_component, bearing_fmu_name, connections

    ssp, case = train_ssp
    with zipfile.ZipFile(ssp) as z:
        names = set(z.namelist())
        root = ET.fromstring(z.read("SystemStructure.ssd"))
    comps = {c.get("name"): c.get("source") for c in root.iterfind(".//ssd:Component", NS)}
    bearings = case.names("bearings")
    assert comps == {"gear_shaft": "resources/GearShaft.fmu", **{
        bearing_component(b): f"resources/{bearing_fmu_name(case[f'bearings.{b}.model'])}.fmu"
        for b in bearings}}
    assert set(comps) >= {"bearing_in_a", "bearing_out_b"}
    assert names == {"SystemStructure.ssd", *comps.values()}
    links = [(c.get("startElement"), c.get("startConnector"), c.get("endElement"),
              c.get("endConnector")) for c in root.iterfind(".//ssd:Connection", NS)]
    assert links == connections(case)
    from fmu_src.build.ssp import read_ssp

    system = read_ssp(ssp, ssp.parent / "read")
    assert [p.name for p in system.bearing_fmus] == [s.rsplit("/", 1)[1] for s in
                                                     list(comps.values())[1:]]
    assert system.case.names("bearings") == bearings


def test_ecos_runs_the_ssp_of_another_train_as_a_jacobi_master_would(train_ecos, train_ssp):
    """ecos (ecospy) runs the two-stage archive with its six bearing FMUs of five models: its
    trajectories equal the emulated Jacobi scheme's
    (:func:`orchestrator.studies.coupling_accuracy.non_iterative`, in-process physics), to
    the film solvers' accuracy, as for the paper's case: the hybrid film starts from its last
    solution and ecos evaluates the bearings along its own sequence, each force within the
    solver's tolerance (1e-8). On the slow output shaft (251 rpm, eccentricity 0.7) that moves
    the hybrid bearing out_b's journal by 8.6e-14 m already in X0 (2.0e-9 of the largest
    position; the paper's case: 3.4e-12), and no more over the steps (positions 2.0e-9,
    velocities 5.1e-8 to 9.9e-8 relative; the bounds of :func:`tests.helpers.film_bounds`,
    not a measurement's)."""
    from orchestrator.studies.coupling_accuracy import non_iterative

    x, ecc = train_ecos
    _, case = train_ssp
    ref = non_iterative(case, TRAIN_STEPS, lag=1)
    scale = np.abs(ref[:, :, :2]).max()
    position = float(np.abs(x[:, :, :2] - ref[:, :, :2]).max() / scale)
    velocity = float(np.abs(x[:, :, 2:] - ref[:, :, 2:]).max() / np.abs(ref[:, :, 2:]).max())
    print(f"\necos vs the emulated Jacobi master, two-stage train, {TRAIN_STEPS} steps: "
          f"positions {position:.1e}, velocities {velocity:.1e}")
    from fmu_src.description import time_step

    bound, v_bound = film_bounds(scale, np.abs(ref[:, :, 2:]).max(), time_step(case))
    print(f"bounds: positions {bound:.1e}, velocities {v_bound:.1e}")
    assert float(np.abs(x[0, :, :2] - ref[0, :, :2]).max() / scale) < bound  # X0
    assert position < bound and velocity < v_bound
    assert np.isfinite(ecc).all() and (ecc > 0).all() and (ecc < 1).all()


def test_the_ecos_command_runs_the_ssp_of_another_train(ecos_cli, train_ssp, train_ecos,
                                                        tmp_path):
    """The ecos command (a C++ process, Python only inside the FMUs) runs the two-stage
    archive: exit 0, and its CSV (6 decimals) shows the eccentricities of the Python-hosted
    run for each of the six bearing components."""
    from fmu_src import description
    from fmu_src.contract import bearing_component

    ssp, case = train_ssp
    _, ecc = train_ecos
    dt = description.time_step(case)
    steps = 12  # ecos 0.7.2's command divides by zero (SIGFPE) below 10 steps
    folder = tmp_path / "run"
    folder.mkdir()
    proc = subprocess.run([str(ecos_cli), "simulate", "--path", str(ssp), "--parameterSet",
                           "case", "--stepSize", repr(dt), "--stopTime", repr(steps * dt)],
                          capture_output=True, text=True, timeout=900, env=_env(), cwd=folder)
    assert proc.returncode == 0, proc.stderr[-2000:]
    bad = [w for w in ("corrupted", "Aborted", "Segmentation", "fatal", "[error]")
           if w in proc.stdout + proc.stderr]
    assert not bad, proc.stderr[-2000:]
    with open(folder / f"{ssp.stem}.csv") as fh:
        rows = [[c.strip() for c in r] for r in csv.reader(fh)]
    assert len(rows) == steps + 2
    header = rows[0]
    for j, b in enumerate(case.names("bearings")):
        col = header.index(f"{bearing_component(b)}::eccentricity[REAL]")
        assert [r[col] for r in rows[1:]] == [f"{v:f}" for v in ecc[:steps + 1, j]], b
