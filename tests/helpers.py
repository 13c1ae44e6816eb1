"""Helpers shared by the test modules (no tests here).

Paths are resolved from this file, never from the working directory.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import numpy as np

from tests.gear_fmu.reference_newmark import NonlinearForce

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"


#: the probes: modules of code the tests run in a fresh interpreter or in their own process
PROBES = ROOT / "tests" / "probes"


#: the hybrid film solver's relative tolerance on the force (tol = 1e-8): two hosts that call
#: the bearings in their own order warm-start it from other solutions, so each force may move
#: by as much; the structure's displacement under a relative change of its loads changes by as
#: much relative to the largest (a stable, damped system over a few steps: no growth), so the
#: positions of two such runs may differ by FILM_BOUND of the largest position
FILM_BOUND = 1e-8


def film_bounds(position_scale: float, velocity_scale: float, dt: float,
                relative: float = FILM_BOUND) -> tuple[float, float]:
    """Bounds on the relative differences of two runs' journal positions and velocities whose
    bearing laws differ by ``relative`` (default :data:`FILM_BOUND`): positions ``relative``
    of the largest ``position_scale`` [m]; velocities what Newmark's velocity update
    (``v1 = 2 (x1 - x0) / dt - v0``, Eq. 12) makes of such a position difference,
    ``2 relative position_scale / dt``, relative to the largest velocity ``velocity_scale``
    [m/s]; ``dt`` the step [s]."""
    return relative, 2.0 * relative * position_scale / (dt * velocity_scale)



def _argv(args) -> list[str]:
    """Command-line arguments of a probe: strings as they are, anything else as JSON."""
    return [a if isinstance(a, str) else json.dumps(a, default=str) for a in args]


def probe_env(env: dict | None = None) -> dict:
    """``env`` (default: this process's environment) with the repository first on
    ``PYTHONPATH``, so that ``python -m tests.probes.<name>`` finds the probes from any
    folder."""
    env = dict(os.environ if env is None else env)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
    return env


def probe_command(module: str, *args, python_args=()) -> list[str]:
    """The command line ``python [python_args] -m <module> <args>`` (arguments as
    :func:`_argv`); run it with ``env=probe_env()``."""
    return [sys.executable, *python_args, "-m", module, *_argv(args)]


def run_isolated(code: str | None = None, timeout: float = 600, numba_cache: Path | None = None,
                 python_args: tuple = (), *, module: str | None = None, script: Path | None = None,
                 args=(), env_vars: dict | None = None) -> dict:
    """Run a probe in a fresh interpreter started in an empty temporary folder; it prints one
    JSON object on its last line and exits normally. Returns that object.

    The probe: ``module`` (``python -m module args``, the repository on the path:
    :func:`probe_env`), or ``script`` (``python script args``, the environment as it is: for
    an interpreter that must not find this repository), or ``code`` (dedented, ``python -c``:
    a line or two; longer code belongs in a probe module, where it is linted and readable).
    ``args`` as :func:`_argv`. ``numba_cache``: numba's cache folder for that interpreter
    (``NUMBA_CACHE_DIR``; an empty one compiles every kernel anew). ``python_args``: options of
    the interpreter (``-S``). ``env_vars``: variables set in the probe's environment."""
    if module is not None:
        env, cmd = probe_env(), probe_command(module, *args, python_args=python_args)
    elif script is not None:
        env, cmd = dict(os.environ), [sys.executable, *python_args, str(script), *_argv(args)]
    else:
        env, cmd = dict(os.environ), [sys.executable, *python_args, "-c", textwrap.dedent(code)]
    if numba_cache is not None:
        env["NUMBA_CACHE_DIR"] = str(numba_cache)
    env.update(env_vars or {})
    with tempfile.TemporaryDirectory(prefix="gsb_test_") as cwd:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=cwd,
                              env=env)
    assert proc.returncode == 0, f"exit code {proc.returncode}: {proc.stderr[-3000:]}"
    return json.loads(proc.stdout.strip().splitlines()[-1])


#: a paced run's coupled steps last at least this long [s]: the run it interrupts cannot end
#: before the test has read its file and signalled it, however fast the machine
PACE = 0.004


def paced_gsb(*args) -> list[str]:
    """The command line of ``gsb *args`` whose coupled steps each last at least :data:`PACE`
    (a sleep before the step: :mod:`tests.probes.standalone.paced_gsb`), with everything else
    as in ``gsb``."""
    script = PROBES / "standalone" / "paced_gsb.py"
    return [sys.executable, str(script), repr(PACE), *map(str, args)]


def run_here(code: str | None = None, *, module: str | None = None, args=()) -> dict:
    """Run a probe in this process and return the JSON object it prints last: ``main(args)``
    of ``module`` (``args`` as :func:`_argv`), or ``code`` (dedented, written for
    :func:`run_isolated`). FMUs may load here: the patched native layer the test FMUs
    carry keeps instances independent and the host alive; a fresh host process is tested where
    it is the point (exit, staging, ``python -S``), and a start-up saved everywhere else."""
    import contextlib
    import importlib
    import io

    with contextlib.redirect_stdout(io.StringIO()) as printed:
        if module is not None:
            importlib.import_module(module).main(_argv(args))
        else:
            exec(textwrap.dedent(code), {"__name__": "__run_here__"})
    return json.loads(printed.getvalue().strip().splitlines()[-1])


def need_threads(n: int) -> None:
    """Skip the test unless numba can give the bearings ``n`` threads here."""
    import numba
    import pytest

    from bearing_fmu.hybrid.model import threading_layer

    if n > 1 and (numba.config.NUMBA_NUM_THREADS < n or threading_layer() is None):
        pytest.skip(f"numba cannot run {n} threads here (NUMBA_NUM_THREADS "
                    f"{numba.config.NUMBA_NUM_THREADS}, threading layer {threading_layer()})")


def numeric_jacobian(model, state, h=1e-6):
    """(2, 4) central-difference dFbar/d(xbar, ybar, xbar_dot, ybar_dot) of a film model's
    force at ``state``: the independent check of analytic Jacobians."""
    out = np.zeros((2, 4))
    for j in range(4):
        sp, sm = list(state), list(state)
        sp[j] += h
        sm[j] -= h
        out[:, j] = (model.dimensionless(*sp, jacobian=False).force
                     - model.dimensionless(*sm, jacobian=False).force) / (2 * h)
    return out


def relative(a, b) -> float:
    """Largest |a - b| relative to the largest |b|."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


def run_paper_case(out_dir, periods, in_process=True, fmu_dir=None, bearing="hybrid",
                   case="baguet2010_spur", steps=None, **overrides):
    """A short run of a shipped case (no figures, no progress): (results dict, summary)."""
    from fmu_src.case import load_case
    from orchestrator.run.results import read_results
    from orchestrator.run.runner import run_case

    run = {"bearings.*.model": bearing, "simulation.mesh_periods": periods}
    s = run_case(load_case(case, (overrides or {}) | run),
                 in_process=in_process, out_dir=out_dir, fmu_dir=fmu_dir, progress=False,
                 steps=steps)
    return read_results(s.results), s


def before_step(monkeypatch, at: int, action) -> None:
    """Call ``action()`` just before the master takes the ``at``-th coupled step of a run from
    t = 0, however the runner asks for it: a block of compiled steps
    (:meth:`orchestrator.coupling.master.Master.steps`) ends before that step, which then goes
    through :meth:`~orchestrator.coupling.master.Master.step`."""
    from orchestrator.coupling import master as master_module

    real_step, real_steps = master_module.Master.step, master_module.Master.steps
    index = at - 1

    def step(self, t, dt):
        if round(t / dt) == index:
            action()
        return real_step(self, t, dt)

    def steps(self, first, dt, n):
        if first <= index < first + n:
            if first == index:
                return None
            n = index - first
        return real_steps(self, first, dt, n)

    monkeypatch.setattr(master_module.Master, "step", step)
    monkeypatch.setattr(master_module.Master, "steps", steps)


def fail_master_step(monkeypatch, at: int) -> None:
    """Make the master's ``at``-th coupled step raise a CouplingError (a run failing midway)."""
    from orchestrator.coupling import master as master_module

    def fail():
        raise master_module.CouplingError("forced failure for the test")

    before_step(monkeypatch, at, fail)


# ----------------------------------------------------------------- the structure written out
T_IN = 220.0  # N m
OMEGA = 325.0  # rad/s


def monolithic_structure(st, bearing_law, meshes=None):
    """Full (reduced) M, C, K, load and nonlinear callback for the generic Newmark step: the
    structure ``st``'s train written out apart from its condensed step.

    C: the structure's damping, with the gyroscopic matrix at the shafts' signed speeds when
    the structure has it. The load: the input torque and the unbalances of Eq. (10) (each
    body's force turning with its shaft's signed speed). The nonlinear force: every mesh,
    evaluated at the structure's kinematics (each mesh's driver angle at t) on its gear
    nodes' DOFs, and the bearings
    ``bearing_law(j, x_j, v_j) -> (force, Kb, Cb)``. ``meshes``: the mesh elements (default:
    copies of the structure's, whose caches are then their own). Its ``active`` is the contact
    sets of all meshes, one after the other."""
    import copy

    from gear_fmu.dofs import U, V, dof
    from gear_fmu.modal.modes import mesh_dofs

    sys_ = st.system
    lay = sys_.layout
    if sys_.load_dof is not None:
        raise ValueError("monolithic_structure: an output clamped (no load torque) only")
    red = sys_.reduced_index
    speeds = st.loads.input_speed * lay.ratios * lay.directions  # signed, per shaft
    c = st.damping_full + (sys_.gyroscopic(speeds) if st.gyroscopic else 0.0)
    m, c, k = (sys_.reduce(a) for a in (sys_.mass, c, sys_.stiffness))
    meshes = copy.deepcopy(st.meshes) if meshes is None else tuple(meshes)
    gears = [red[mesh_dofs(sys_, i)] for i in range(len(meshes))]
    brg = red[sys_.bearing_dofs]
    n = m.shape[0]
    bodies = [*zip(lay.gears, sys_.gear_nodes, strict=True),
              *zip(lay.discs, sys_.disc_nodes, strict=True)]
    unbalances = []
    for body, node in bodies:
        if body.unbalance > 0.0:
            mass = body.mass if body.unbalance_mass == "body" else lay.carried_mass(body.shaft)
            w = speeds[lay.shaft_index[body.shaft]]
            unbalances.append((red[dof(node, U)], red[dof(node, V)],
                               mass * body.unbalance * w * w, w, body.unbalance_phase))
    gravity = np.zeros(n)
    if st.loads.gravity is not None:
        g = np.zeros(sys_.n_dof)
        g[U:6 * sys_.n_nodes:6], g[V:6 * sys_.n_nodes:6] = st.loads.gravity
        gravity = sys_.reduce(sys_.mass @ g)

    def force(t):  # Eq. (10) written out here independently
        f = gravity.copy()
        f[red[sys_.torque_dof]] += st.loads.torque
        for iu, iv, amplitude, w, phase in unbalances:
            f[iu] += amplitude * math.cos(w * t + phase)
            f[iv] += amplitude * math.sin(w * t + phase)
        return f

    def nonlinear_at(t):
        angles = st.mesh_angles(st.input_angle(t))

        def nl(x, v):
            f = np.zeros(n)
            dx = np.zeros((n, n))
            dv = np.zeros((n, n))
            active = []
            for mesh, gear, angle in zip(meshes, gears, angles, strict=True):
                ms = mesh.evaluate(float(angle), x[gear])
                f[gear] += ms.force
                dx[np.ix_(gear, gear)] -= ms.stiffness
                active.append(ms.active)
            for j in range(len(brg)):
                fb, kb, cb = bearing_law(j, x[brg[j]], v[brg[j]])
                f[brg[j]] += fb
                dx[np.ix_(brg[j], brg[j])] -= kb
                dv[np.ix_(brg[j], brg[j])] -= cb
            return NonlinearForce(f, dx, dv, np.concatenate(active))
        return nl

    return m, c, k, force, nonlinear_at


def affine(f0, kb, cb):
    def law(j, x, v):
        return f0[j] - kb[j] @ x - cb[j] @ v, kb[j], cb[j]
    return law
