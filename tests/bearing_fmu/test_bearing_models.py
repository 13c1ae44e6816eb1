"""Every registered bearing model (bearing_fmu.MODELS) honours the one contract.

For each model, built by the registry's ``from_parameters`` with its default options:

* a finite force, stiffness and damping at a loaded, moving journal state (SI, local frame);
* the same law in a rotated or mirrored frame through ``evaluate_global`` (what the bearing
  sets and FMUs call; one compiled call for the hybrid model), and the film models' error off
  the clearance;
* Kb = -dF/dX and Cb = -dF/dXdot against central differences of its own force;
* through the FMU built for it: one coupled static solution and Newmark step of the paper's
  spur case equal to the same step in-process.

A model added to the registry is tested here without touching this file.
"""


import numpy as np
import pytest

from bearing_fmu import (
    MODELS,
    BearingData,
    EccentricityError,
    is_film_model,
    model_class,
)
from bearing_fmu.frames import LocalFrame
from fmu_src.build.fmus import FMUS
from fmu_src.contract import bearing_fmu_name
from tests.helpers import relative

BEARING = BearingData(diameter=0.070, length=0.050, clearance=150e-6, viscosity=0.0288)
OMEGA = 325.0  # rad/s
C = BEARING.clearance
STATE = (0.35 * C, -0.55 * C, 0.02 * C * OMEGA, -0.01 * C * OMEGA)  # m, m/s (eccentricity 0.65)

#: central-difference step (in units of C and C omega) and, for the film models, the largest
#: disagreement measured with it (relative to the largest entry of Kb or Cb: the truncation
#: O(step^2) and the solvers' tolerances), asserted with a margin of 3; for the affine models
#: the differences are round-off only, bounded by :func:`affine_roundoff`
FD_STEP = 1e-4
MEASURED_JACOBIAN = {"hybrid": 6.8e-8, "short": 1.4e-7, "fd": 7.6e-8}
EPS = float(np.finfo(float).eps)


def affine_roundoff(r) -> tuple[float, float]:
    """Bounds on the central differences' error for an affine law (no truncation), relative to
    the largest entry of Kb and of Cb: each force rounds its sum of at most four products to
    4 eps of the largest term (at most ``T = max(|F|, |Kb| C, |Cb| C omega)`` here, the
    state being within C and C omega), the difference of two of them is divided by
    ``2 FD_STEP C`` (Kb) or ``2 FD_STEP C omega`` (Cb); 8 eps T over that."""
    k, c = np.abs(r.stiffness).max(), np.abs(r.damping).max()
    t = max(np.abs(r.force).max(), k * C, c * C * OMEGA)
    return (8 * EPS * t / (2 * FD_STEP * C * k),
            8 * EPS * t / (2 * FD_STEP * C * OMEGA * c) if c > 0 else 0.0)


def built(name):
    model = model_class(name).from_parameters(BEARING)
    # the linear model is its film until the static position is known: freeze it there
    model.end_initialization(STATE[0], STATE[1], OMEGA)
    return model


def central_differences(model, state, step):
    """(2, 4) -dF/d(x, y, xdot, ydot) by central differences of the SI force."""
    scales = (C, C, C * OMEGA, C * OMEGA)
    out = np.zeros((2, 4))
    for j in range(4):
        sp, sm = list(state), list(state)
        sp[j] += step * scales[j]
        sm[j] -= step * scales[j]
        fp = model.evaluate(*sp, OMEGA).force
        fm = model.evaluate(*sm, OMEGA).force
        out[:, j] = -(fp - fm) / (2.0 * step * scales[j])
    return out


def test_every_model_has_an_fmu_and_declared_options():
    assert set(MODELS) == {"hybrid", "short", "fd", "linear", "lumped"}
    for name in MODELS:
        cls = model_class(name)
        assert cls.name == name and bearing_fmu_name(name) in FMUS
        assert set(cls.option_defaults()) == {o.key for o in cls.options}


@pytest.mark.parametrize("name", list(MODELS))
def test_force_and_jacobians_against_central_differences(name):
    model = built(name)
    # the second call at the state: the Jacobians of a converged solve (a cold call may end
    # with the hybrid model's corrector, whose Jacobians are off by O(dt): test_hybrid.py)
    model.evaluate(*STATE, OMEGA)
    r = model.evaluate(*STATE, OMEGA)
    assert all(np.all(np.isfinite(a)) for a in (r.force, r.stiffness, r.damping))
    assert np.hypot(*r.force) > 0.0
    num = central_differences(model, STATE, FD_STEP)
    err_k = relative(r.stiffness, num[:, :2])
    err_c = relative(r.damping, num[:, 2:]) if np.abs(num[:, 2:]).max() > 0 else \
        float(np.abs(r.damping).max())
    print(f"\n{name}: Kb {err_k:.1e}, Cb {err_c:.1e} against central differences")
    if name in MEASURED_JACOBIAN:
        limit_k = limit_c = 3.0 * MEASURED_JACOBIAN[name]
    else:
        limit_k, limit_c = affine_roundoff(r)
        print(f"round-off bounds: Kb {limit_k:.1e}, Cb {limit_c:.1e}")
    assert err_k <= limit_k and err_c <= limit_c


#: bound on the difference between ``evaluate_global`` and ``evaluate`` turned back by numpy
#: over the frames of FRAMES (relative to the largest entry): the two routes round the local
#: state and the rotations differently in the last bits. A closed-form law (short, linear,
#: lumped) carries that round-off through a few dozen operations: 64 eps (measured 1.5e-15,
#: 1.1e-15, 3.8e-16). The iterative film solvers carry it to their own tolerance: the hybrid
#: model's on t and the force, 1e-8 (measured 2.3e-14); the FD model's Jacobians are
#: differences of perturbed solves converged to jacobian_tol = 1e-12 over jacobian_step =
#: 1e-5, 1e-7 (measured 1.4e-10)
FRAME_BOUND = {"hybrid": 1e-8, "short": 64 * EPS, "fd": 1e-12 / 1e-5, "linear": 64 * EPS,
               "lumped": 64 * EPS}
FRAMES = [LocalFrame(float(a), sign) for a in np.linspace(0.1, 6.2, 8) for sign in (1, -1)]


@pytest.mark.parametrize("name", list(MODELS))
def test_global_frame_law_is_the_rotated_local_law(name):
    """``evaluate_global`` against ``evaluate`` in the local frame turned back by numpy
    (F = Q^T F_loc, K = Q^T K_loc Q), each on a fresh model: bit for bit in the axis frames of
    the paper's bearings (angle 0, either sense of rotation), to :data:`FRAME_BOUND` in
    turned ones; a film model refuses a state off the clearance circle in any frame."""
    worst = 0.0
    for frame in [LocalFrame(0.0, 1), LocalFrame(0.0, -1), *FRAMES]:
        pos, vel = frame.to_global(STATE[:2]), frame.to_global(STATE[2:])
        r = built(name).evaluate(*frame.to_local(pos), *frame.to_local(vel), OMEGA)
        out = np.empty((5, 2))
        built(name).evaluate_global(frame.q, np.concatenate([pos, vel]), OMEGA, out)
        expected = (frame.to_global(r.force), frame.matrix_to_global(r.stiffness),
                    frame.matrix_to_global(r.damping))
        diff = max(float(np.abs(got - ref).max() / max(np.abs(ref).max(), 1e-300))
                   for got, ref in zip((out[0], out[1:3], out[3:5]), expected, strict=True))
        if frame.angle == 0.0:
            assert diff == 0.0, (name, frame, diff)
        worst = max(worst, diff)
        if is_film_model(name):  # a constant-coefficient law holds anywhere
            far = frame.to_global((1.01 * C, 0.0))
            with pytest.raises(EccentricityError, match="must be < 1"):
                built(name).evaluate_global(frame.q, np.array([*far, 0.0, 0.0]), OMEGA, out)
    print(f"\n{name}: largest difference in turned frames {worst:.2e}")
    assert worst <= FRAME_BOUND[name]


@pytest.mark.parametrize("name", list(MODELS))
def test_one_coupled_step_through_its_fmu_equals_in_process(name, fmu_dir):
    """Static solution and the first Newmark step of the spur case, FMUs vs in-process: the
    same bits (the same code, the same calls)."""
    from fmu_src.case import load_case
    from fmu_src.description import time_step
    from orchestrator.coupling.system import build_master

    case = load_case("baguet2010_spur")
    res = {}
    for in_process in (True, False):
        m = build_master(case.with_overrides({"bearings.*.model": name}), in_process=in_process,
                         fmu_dir=fmu_dir)
        try:
            static = m.solve_static()
            m.exit_initialization()
            step = m.step(0.0, time_step(case))
        finally:
            m.close()
        res[in_process] = (static.states, step.states, step.iterations)
    (x0_in, x1_in, it_in), (x0_fmu, x1_fmu, it_fmu) = res[True], res[False]
    assert np.all(np.isfinite(x1_in)) and it_fmu == it_in
    np.testing.assert_array_equal(x0_fmu, x0_in)
    np.testing.assert_array_equal(x1_fmu, x1_in)
