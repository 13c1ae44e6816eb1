"""Exact mean mesh stiffness, damped modes of the linearised system (Eq. 20), tooth critical
speeds, ``gsb modal`` text / JSON / Campbell output."""

import json
import math

import numpy as np
import pytest

from fmu_src import description
from fmu_src.case import load_case
from fmu_src.examples import paper_system
from gear_fmu.modal.analyses import (
    _springs,
    damped,
    exact_mean_mesh_stiffness,
    line_of_action_stiffness,
    mean_mesh_stiffness,
)
from gear_fmu.modal.damped_modes import damped_eigen, damped_modes, tooth_critical_speeds
from gear_fmu.modal.modes import mesh_dofs, modal_damping_matrix, natural_modes
from orchestrator.cli import main

SPUR = "baguet2010_spur"


@pytest.fixture(scope="module")
def spur_structure():
    return description.structure(load_case(SPUR))


# ------------------------------------------------------------------ exact mean mesh stiffness
def test_exact_mean_mesh_stiffness_against_a_fine_time_average(spur_structure):
    """Gauss-Legendre between the contact events against the midpoint rule on 4096 equally
    spaced angles of one mesh period (error O(1/N): the stiffness jumps twice per period)."""
    st = spur_structure
    before = st.get_state()
    exact = exact_mean_mesh_stiffness(st, 1e8)
    after = st.get_state()
    assert after.t == before.t and after.mesh_states is None and np.all(after.x == before.x)
    assert exact.shape == (1, 12, 12)  # the paper's train: one mesh
    exact = exact[0]
    f0, kb = _springs(st, 1e8)
    # one mesh, its pinion on the input shaft: the mesh angle is the input angle
    assert st.mesh_angles(1.0).tolist() == [1.0]
    a0, period, n = st.input_angle(st.t), st.meshes[0].event_period, 4096
    grid = np.zeros((12, 12))
    for i in range(n):
        st.static_at(f0, kb, a0 + period * (i + 0.5) / n)
        grid += st.mesh_states[0].stiffness
    grid /= n
    scale = np.abs(exact).max()
    err = np.abs(grid - exact).max() / scale
    # measured 5.29e-5 (largest entry error over the largest entry); 6e-5 leaves 13 % margin
    assert err < 6e-5
    # the 16 equally spaced angles of the modal damping reference are off by 1.36e-2
    coarse = np.abs(mean_mesh_stiffness(st, 1e8)[0] - exact).max() / scale
    assert coarse > 100 * 6e-5
    per_width = line_of_action_stiffness(st, exact) / st.meshes[0].pair.contact_width / 1e9
    print(f"\nexact mean {per_width:.4f} N/(mm um); 4096-angle grid error {err:.2e}, "
          f"16 angles {coarse:.2e}")
    assert per_width == pytest.approx(20.33, abs=0.01)


def test_line_of_action_stiffness_is_the_sum_of_the_slice_springs(spur_structure):
    """K[theta1, theta1] / (r_b1 cos beta_b)^2 equals sum k dl = sum load / delta of the
    slices in contact (closed form of the involute: V[theta1] = r_b1 cos beta_b)."""
    st = spur_structure
    f0, kb = _springs(st, 1e8)
    saved = st.get_state()
    try:
        for frac in (0.1, 0.9):  # one and two tooth pairs in contact
            st.static_at(f0, kb, st.input_angle(st.t) + frac * st.meshes[0].event_period)
            (ms,) = st.mesh_states
            springs = float(np.sum(ms.load[ms.active] / ms.delta[ms.active]))
            assert line_of_action_stiffness(st, ms.stiffness) == pytest.approx(springs,
                                                                               rel=1e-12)
    finally:
        st.set_state(saved)
    with pytest.raises(ValueError, match=r"shape \(3, 3\)"):
        line_of_action_stiffness(st, np.zeros((3, 3)))
    with pytest.raises(ValueError, match="n_gauss = 0"):
        exact_mean_mesh_stiffness(st, 1e8, n_gauss=0)


# ------------------------------------------------------------------ damped modes, closed forms
def _root(omega, zeta):
    return complex(-zeta * omega, omega * math.sqrt(1.0 - zeta**2))


def test_uncoupled_two_dof_roots_and_mesh_share():
    """Two single-DOF oscillators: lambda = -zeta w + i w sqrt(1 - zeta^2), w = sqrt(k/m),
    zeta = c / (2 sqrt(k m)); the second carries a 'mesh' spring km of its stiffness."""
    m1, k1, c1 = 2.0, 8e5, 40.0
    m2, k2a, km, c2 = 3.0, 2e6, 1e6, 300.0
    k2 = k2a + km
    found = damped_eigen(np.diag([m1, m2]), np.diag([c1, c2]), np.diag([k1, k2]),
                         np.diag([0.0, km]), dof_kind=[0, 1])
    w1, w2 = math.sqrt(k1 / m1), math.sqrt(k2 / m2)
    expected = [_root(w1, c1 / (2 * math.sqrt(k1 * m1))), _root(w2, c2 / (2 * math.sqrt(k2 * m2)))]
    np.testing.assert_allclose(found.eigenvalues, expected, rtol=1e-12)
    np.testing.assert_allclose(found.mesh_energy_fraction, [0.0, km / k2], atol=1e-12)
    assert found.kinds == ["bending", "torsion"]
    assert not found.overdamped.any() and found.n_rigid == 0
    np.testing.assert_allclose(found.damping_ratio, [c1 / (2 * math.sqrt(k1 * m1)),
                                                     c2 / (2 * math.sqrt(k2 * m2))], rtol=1e-12)


def test_proportionally_damped_two_dof_chain():
    """Chain ground-k1-m1-k2-m2, C = alpha M + beta K: w^2 from the quadratic
    m1 m2 w^4 - (m1 k22 + m2 k11) w^2 + det K = 0, zeta_i = alpha / (2 w_i) + beta w_i / 2."""
    m1, m2, k1, k2 = 1.5, 0.7, 3e6, 1.2e6
    alpha, beta = 20.0, 2e-5
    mm = np.diag([m1, m2])
    kk = np.array([[k1 + k2, -k2], [-k2, k2]])
    a, b, c = m1 * m2, -(m1 * kk[1, 1] + m2 * kk[0, 0]), kk[0, 0] * kk[1, 1] - k2**2
    w = np.sqrt([(-b - math.sqrt(b * b - 4 * a * c)) / (2 * a),
                 (-b + math.sqrt(b * b - 4 * a * c)) / (2 * a)])
    zeta = alpha / (2 * w) + beta * w / 2
    found = damped_eigen(mm, alpha * mm + beta * kk, kk)
    np.testing.assert_allclose(found.eigenvalues, [_root(wi, zi) for wi, zi in
                                                   zip(w, zeta, strict=True)], rtol=1e-11)
    assert found.kinds == ["unclassified"] * 2
    np.testing.assert_array_equal(found.mesh_energy_fraction, [0.0, 0.0])


def _quartic(m, c, k):
    """det(lambda^2 M + lambda C + K) of 2x2 matrices, expanded by hand (highest power first)."""
    return [
        m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0],
        m[0, 0] * c[1, 1] + c[0, 0] * m[1, 1] - m[0, 1] * c[1, 0] - c[0, 1] * m[1, 0],
        m[0, 0] * k[1, 1] + c[0, 0] * c[1, 1] + k[0, 0] * m[1, 1]
        - m[0, 1] * k[1, 0] - c[0, 1] * c[1, 0] - k[0, 1] * m[1, 0],
        c[0, 0] * k[1, 1] + k[0, 0] * c[1, 1] - c[0, 1] * k[1, 0] - k[0, 1] * c[1, 0],
        k[0, 0] * k[1, 1] - k[0, 1] * k[1, 0],
    ]


@pytest.mark.parametrize("c22", [60.0, 2000.0])
def test_non_proportional_two_dof_against_the_characteristic_quartic(c22):
    """Non-symmetric K (a fluid film's), non-proportional C, coupled M: the roots with
    Im >= 0 of det(lambda^2 M + lambda C + K) = 0. c22 = 2000 N s/m makes the second DOF
    over-damped: two real roots, flagged."""
    m = np.array([[1.0, 0.1], [0.1, 1.0]])
    k = np.array([[5e4, -1e4], [-0.5e4, 3e4]])
    c = np.array([[30.0, -10.0], [-10.0, c22]])
    roots = np.roots(_quartic(m, c, k))
    roots = roots[roots.imag >= -1e-9 * np.abs(roots)]
    found = damped_eigen(m, c, k)
    assert found.eigenvalues.size == roots.size
    osc, real = roots[np.abs(roots.imag) > 1e-9 * np.abs(roots)], roots[
        np.abs(roots.imag) <= 1e-9 * np.abs(roots)]
    assert found.overdamped.sum() == real.size == (2 if c22 > 1000 else 0)
    got = found.eigenvalues
    np.testing.assert_allclose(got[~found.overdamped], osc[np.argsort(osc.imag)], rtol=1e-10)
    np.testing.assert_allclose(np.sort(got[found.overdamped].real), np.sort(real.real),
                               rtol=1e-10)
    assert np.all(found.damping_ratio[found.overdamped] == 1.0)
    assert np.all(found.frequency_hz[found.overdamped] == 0.0)


def test_two_inertias_on_a_mesh_spring():
    """J1, J2 joined by a mesh spring k along base radii r1, r2 (deflection r1 th1 + r2 th2),
    with a mesh damper c: one mode at w^2 = k (r1^2/J1 + r2^2/J2), zeta = c w / (2 k) (C
    proportional to K), shape th2/th1 = (r2/J2)/(r1/J1), all its strain in the mesh; the rigid
    rotation (a double zero root) is left out."""
    j1, j2, r1, r2, k = 3.77e-3, 4.50, 0.0489, 0.295, 8e8
    v = np.array([r1, r2])
    w = math.sqrt(k * (r1**2 / j1 + r2**2 / j2))
    zeta = 0.05
    c = 2 * zeta * k / w
    kk = k * np.outer(v, v)
    found = damped_eigen(np.diag([j1, j2]), c * np.outer(v, v), kk, kk, dof_kind=[1, 1])
    assert found.n_rigid == 2 and found.eigenvalues.size == 1
    assert found.eigenvalues[0] == pytest.approx(_root(w, zeta), rel=1e-12)
    phi = found.shapes[:, 0]
    assert (phi[1] / phi[0]).real == pytest.approx((r2 / j2) / (r1 / j1), rel=1e-12)
    assert found.mesh_energy_fraction[0] == pytest.approx(1.0, rel=1e-12)
    assert found.kinds == ["torsion"]
    print(f"\ntwo-inertia mesh mode {w / 2 / math.pi:.1f} Hz")


def test_damped_eigen_bad_input():
    with pytest.raises(ValueError, match=r"damping matrix shape \(3, 3\) must be \(2, 2\)"):
        damped_eigen(np.eye(2), np.eye(3), np.eye(2))
    with pytest.raises(ValueError, match="not positive definite"):
        damped_eigen(-np.eye(2), np.eye(2), np.eye(2))


# ------------------------------------------------------------------ the gear-shaft system
SYSTEM = paper_system(n_elements=8)


def _mesh_k():
    n = np.array([math.sin(math.radians(20)), math.cos(math.radians(20)), 0.0])
    r1, r2 = 0.052, 0.314
    v = np.concatenate([n, np.cross([r1, 0, 0], n), -n, -np.cross([-r2, 0, 0], n)])
    return 5e8 * np.outer(v, v)


def test_modal_damping_on_the_same_configuration_gives_zeta_on_every_mode():
    """C built on the undamped modes of the same K, no bearing damping: every damped root has
    ratio zeta and f_d = f_n sqrt(1 - zeta^2); mesh shares as the undamped modes'."""
    zeta, mesh_k = 0.03, _mesh_k()
    und = natural_modes(SYSTEM, 1e8, mesh_k)
    c = modal_damping_matrix(SYSTEM, und, zeta)
    found = damped_modes(SYSTEM, c, mesh_k, 1e8, 0.0)
    np.testing.assert_allclose(found.damping_ratio, zeta, rtol=1e-6)
    np.testing.assert_allclose(found.frequency_hz, und.frequency_hz * math.sqrt(1 - zeta**2),
                               rtol=1e-8)
    np.testing.assert_allclose(found.mesh_energy_fraction, und.mesh_energy_fraction,
                               atol=1e-8)
    assert found.kinds == und.kinds


def _backward_errors(m, c, k, lam, phi):
    """Normwise backward error of each eigenpair of ``(lambda^2 M + lambda C + K) phi = 0``
    (Tisseur, Linear Algebra Appl. 309 (2000) 339-361, Thm 1):
    ``eta = ||Q(lambda) phi|| / ((|lambda|^2 ||M|| + |lambda| ||C|| + ||K||) ||phi||)``, 2-norms:
    the smallest relative perturbation of M, C and K of which (lambda, phi) is an exact
    eigenpair."""
    q = (m @ phi) * lam**2 + (c @ phi) * lam + k @ phi
    norms = [np.linalg.norm(a, 2) for a in (m, c, k)]
    a = np.abs(lam)
    return np.linalg.norm(q, axis=0) / ((a * a * norms[0] + a * norms[1] + norms[2])
                                        * np.linalg.norm(phi, axis=0))


def test_full_bearing_blocks_enter_unsymmetrised():
    """Non-symmetric Kb and Cb per bearing: each root and shape is an exact eigenpair of
    (lambda^2 M + lambda (C + Cb) + K_shaft + K_mesh + Kb) phi = 0, the blocks placed by hand
    on the bearing DOFs, to round-off: the pair's normwise backward error (its distance to that
    problem, relative to the norms of M, C and K) is within what a backward-stable
    eigensolver leaves."""
    rng = np.random.default_rng(1)
    kb = 1e8 * (np.eye(2) + 0.4 * rng.standard_normal((4, 2, 2)))
    cb = 1e5 * (np.eye(2) + 0.3 * rng.standard_normal((4, 2, 2)))
    mesh_k = _mesh_k()
    c = modal_damping_matrix(SYSTEM, natural_modes(SYSTEM, 1e8, mesh_k), 0.03)
    found = damped_modes(SYSTEM, c, mesh_k, kb, cb)
    k = SYSTEM.stiffness.copy()
    cc = c.copy()
    g = mesh_dofs(SYSTEM, 0)
    k[np.ix_(g, g)] += mesh_k
    for j in range(4):
        u, v = SYSTEM.bearing_dofs[j]
        for a, p in enumerate((u, v)):
            for b, q in enumerate((u, v)):
                k[p, q] += kb[j, a, b]
                cc[p, q] += cb[j, a, b]
    f = SYSTEM.free
    m, k, cc = SYSTEM.mass[np.ix_(f, f)], k[np.ix_(f, f)], cc[np.ix_(f, f)]
    eta = _backward_errors(m, cc, k, found.eigenvalues, found.shapes[f])
    eps = np.finfo(float).eps
    # The bound is LAPACK's acceptance of its own eigensolvers (the test programs of dgeev
    # and dggev pass a residual ratio ||A z - lambda z|| / (n eps ||A|| ||z||) below the
    # threshold 30 of their input files): 30 n eps with n = 2 x 107, the size of the
    # first-order system damped_eigen hands to LAPACK, 1.4e-12. Measured largest: 1.2e-15
    # (5.6 eps; numpy 2.4, scipy 1.17) and 1.4e-15 (numpy 1.26, scipy 1.11), a thousandth of
    # it. (The earlier check scaled each
    # residual by the mode's largest term, which is not what the solver's error scales with:
    # 7.6e-11 here, 2.9e-10 with numpy 1.26 and scipy 1.11, against a bound of 4e-10.) A
    # misplaced or symmetrised block leaves a backward error of the order of the skew parts
    # over the norms: 2.1e-4 measured for the symmetrised blocks below (> 1e-5 asserted).
    bound = 30 * 2 * f.size * eps
    print(f"\nlargest normwise backward error {eta.max():.1e} ({eta.max() / eps:.1f} eps; "
          f"bound {bound:.1e})")
    assert eta.max() < bound
    # the roots with symmetrised blocks do not solve it (so the skew parts are used)
    sym = damped_modes(SYSTEM, c, mesh_k, 0.5 * (kb + kb.transpose(0, 2, 1)),
                       0.5 * (cb + cb.transpose(0, 2, 1)))
    assert _backward_errors(m, cc, k, sym.eigenvalues, sym.shapes[f]).max() > 1e-5


# ------------------------------------------------------------------ tooth critical speeds
def test_tooth_critical_speeds_against_hand_made_modes():
    """z1 = 25. Mode 1: 2 pi f / z1 = 600 rad/s -> k = 1..4 at 600, 300, 200, 150 rad/s;
    mode 2: mesh share 0.05 < 0.1, left out; mode 3: share exactly 0.1, 2 pi f / z1 = 1000 ->
    500, 333.3, 250 rad/s; mode 4: over-damped (f = 0). Range 160-650 rad/s."""
    z1 = 25
    f = np.array([600.0, 400.0, 1000.0, 0.0]) * z1 / (2 * math.pi)
    rows = tooth_critical_speeds(f, [0.1, 0.2, 0.05, 1.0], [0.5, 0.05, 0.1, 0.3], z1,
                                 (160.0, 650.0))
    got = [(r["mode"], r["harmonic"], r["speed_rad_s"]) for r in rows]
    expected = [(1, 3, 200.0), (3, 4, 250.0), (1, 2, 300.0), (3, 3, 1000.0 / 3), (3, 2, 500.0),
                (1, 1, 600.0)]
    assert [g[:2] for g in got] == [e[:2] for e in expected]
    np.testing.assert_allclose([g[2] for g in got], [e[2] for e in expected], rtol=1e-14)
    for r in rows:
        assert r["speed_rpm"] == pytest.approx(r["speed_rad_s"] * 30 / math.pi, rel=1e-14)
        assert r["harmonic"] * z1 * r["speed_rad_s"] / (2 * math.pi) == pytest.approx(
            r["frequency_hz"], rel=1e-14)
    assert rows[0]["damping_ratio"] == 0.1 and rows[1]["mesh_energy_fraction"] == 0.1
    assert len(tooth_critical_speeds(f, [0.1] * 4, [0.5] * 4, z1, (160.0, 650.0),
                                     min_mesh_fraction=0.6)) == 0
    with pytest.raises(ValueError, match=r"speed range \(650.0, 160.0\) rad/s"):
        tooth_critical_speeds(f, [0.1] * 4, [0.5] * 4, z1, (650.0, 160.0))
    with pytest.raises(ValueError, match=r"min_mesh_fraction = 1\.5"):
        tooth_critical_speeds(f, [0.1] * 4, [0.5] * 4, z1, min_mesh_fraction=1.5)


# ------------------------------------------------------------------ gsb modal
def test_gsb_modal_json_is_one_object_with_the_damped_modes(capsys):
    assert main(["modal", SPUR, "--bearing", "linear", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)  # the whole stdout is one JSON object
    [mesh] = out["meshes"]  # the pair's one mesh
    assert mesh["mesh"] == "mesh" and mesh["driver_teeth"] == 26 and mesh["speed_ratio"] == 1.0
    assert mesh["mean_mesh_stiffness_N_per_m"] == pytest.approx(20.33e9 * 0.04, rel=1e-3)
    damped = out["damped_modes"]
    assert {"frequency_hz", "damping_ratio", "mesh_energy_fraction", "kind"} <= set(damped[0])
    # every oscillating mode's whirl named; the paper's case keeps the paper's choice
    assert {d["whirl"] for d in damped if not d["overdamped"]} <= {"forward", "backward",
                                                                   "mixed", "none"}
    assert out["gyroscopic"] is False
    osc = [d["frequency_hz"] for d in damped if not d["overdamped"]]
    assert osc == sorted(osc) and osc[0] > 0.0
    mesh = [d for d in damped if (d["mesh_energy_fraction"] or 0.0) >= 0.1 and
            not d["overdamped"]]
    assert len(mesh) >= 1
    assert {"frequency_hz", "kind", "mesh_energy_fraction"} <= set(out["undamped_modes"][0])
    low, high = out["speed_range_rad_s"]
    assert out["critical_speeds"]
    for r in out["critical_speeds"]:
        mode = damped[r["mode"] - 1]
        assert mode["frequency_hz"] == r["frequency_hz"] and mode["mesh_energy_fraction"] >= 0.1
        assert low <= r["speed_rad_s"] <= high
        assert r["speed_rad_s"] == pytest.approx(
            2 * math.pi * r["frequency_hz"] / (r["harmonic"] * 26), rel=1e-14)
    assert out["campbell"] is None


def test_gsb_modal_prints_the_three_tables(capsys):
    assert main(["modal", SPUR, "--bearing", "linear", "--modes", "14"]) == 0
    out = capsys.readouterr().out
    assert "N/(mm um)" in out and "16 equally spaced angles" in out
    assert "f_d [Hz]  zeta [-]  mesh [-]  whirl     type" in out
    assert "omega [rad/s]   N [rpm]" in out
    assert "torsion-bending" in out


@pytest.mark.parametrize(("argv", "message"), [
    (["--bearing-stiffness", "-1"], "--bearing-stiffness -1.0 N/m must be finite and > 0"),
    (["--speed-range", "500", "100"], "HIGH = 100.0 rad/s must be finite and > LOW = 500.0"),
    (["--speed-range", "0", "100"], "LOW = 0.0 rad/s must be finite and > 0"),
    (["--mesh-fraction", "2"], "--mesh-fraction 2.0 must lie in [0, 1]"),
    (["--campbell-speeds", "1"], "--campbell-speeds 1 must lie in [3, 200]"),
])
def test_gsb_modal_bad_options_are_one_line_errors(capsys, argv, message):
    assert main(["modal", SPUR, *argv]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    err = captured.err.strip()
    assert message in err and "\n" not in err and "Traceback" not in err


def test_gsb_modal_isotropic_bearings_have_no_bearing_damping(capsys):
    assert main(["modal", SPUR, "--bearing-stiffness", "1e9", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert "isotropic 1e+09 N/m, no bearing damping (Cb = 0)" in out["bearings"]
    # modal damping 0.03 on the modes of K with the 16-angle mean mesh stiffness, no Cb: the
    # damped modes (exact mean) have zeta 0.03 but for the mesh modes, which see the 1.4 %
    # stiffer reference mesh: measured largest deviation 5.1e-3 of 0.03, limit 6e-3
    zeta = np.array([d["damping_ratio"] for d in out["damped_modes"]])
    assert np.abs(zeta / 0.03 - 1.0).max() < 6e-3


def test_damped_modes_of_the_structure_with_its_own_damping_reference(spur_structure):
    """Isotropic bearings, no Cb, C built by the structure on the modes of its reference
    configuration: with the reference's mesh stiffness every damped mode has zeta 0.03."""
    st = spur_structure
    st.set_damping_reference(1e9)
    found = damped(st, 1e9, 0.0, mesh_stiffness=st.reference_mesh_stiffness)
    np.testing.assert_allclose(found.damping_ratio, 0.03, rtol=1e-6)
    exact = damped(st, 1e9, 0.0)  # the exact mean: mesh modes differ
    assert np.abs(exact.damping_ratio / 0.03 - 1.0).max() > 1e-3


def test_gsb_modal_campbell_at_three_speeds(tmp_path, capsys):
    png = tmp_path / "campbell.png"
    assert main(["modal", SPUR, "--bearing", "linear", "--json", "--campbell", str(png),
                 "--campbell-speeds", "3", "--speed-range", "100", "900"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert png.is_file() and png.stat().st_size > 20_000
    chart = out["campbell"]
    assert chart["path"] == str(png) and chart["speeds_rad_s"] == [100.0, 500.0, 900.0]
    for c in chart["crossings"]:
        # order: cycles per input revolution, k z1 on the mesh lines, each shaft's ratio on 1x
        slope = c["harmonic"] * 26 if c["harmonic"] else {"pinion_shaft": 1.0,
                                                          "gear_shaft": 26 / 157}[c["shaft"]]
        assert c["order"] == pytest.approx(slope, rel=1e-12)
        assert c["frequency_hz"] == pytest.approx(slope * c["speed_rad_s"] / (2 * math.pi))
        assert 100.0 <= c["speed_rad_s"] <= 900.0
    # the mesh modes near 2.2 and 4.4 kHz meet the harmonics k >= 2 inside 100-900 rad/s
    assert any(c["harmonic"] >= 2 and c["mesh"] == "mesh" for c in chart["crossings"])
    # linearised film bearings, every mode damped from 100 to 900 rad/s
    assert chart["stability_threshold_rad_s"] is None


def test_gsb_modal_campbell_writes_into_results_and_says_why_its_crossings_differ(
        tmp_path, capsys, monkeypatch):
    """Without a file name the diagram goes into --out, by default ``results`` (gsb run's
    folder), never the current folder itself; the line naming it says that its crossings
    follow the speed-dependent modes, unlike the table of the modes at the case's speed."""
    monkeypatch.chdir(tmp_path)
    assert main(["modal", SPUR, "--bearing", "linear", "--campbell", "--campbell-speeds", "3",
                 "--speed-range", "100", "900"]) == 0
    printed = capsys.readouterr().out
    assert (tmp_path / "results" / f"{SPUR}_campbell.png").is_file()
    assert not list(tmp_path.glob("*.png"))
    assert "whose modes are those at the case's 325 rad/s" in printed
    assert "campbell: stable: every mode's damping ratio is positive at every speed 100-900" \
        in printed
    assert "campbell critical speeds (a mode followed over speed crossing an excitation line" \
        in printed and "mesh k=2" in printed
