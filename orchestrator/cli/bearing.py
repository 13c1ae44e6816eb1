"""``gsb bearing``: a journal-bearing calculator on top of :mod:`bearing_fmu`.

Two forms:

* dimensionless: journal at (eps, 0), zero velocity, for a given L/D: force, Sommerfeld number,
  attitude angle, stiffness and damping matrices (paper scale and load-normalised);
* dimensional: D, L, C, mu, speed and load -> static equilibrium (Eq. 8), eccentricity ratio,
  attitude angle and the 8 coefficients in SI units.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from bearing_fmu import MODELS, BearingData, is_film_model, model_class
from bearing_fmu.static import static_equilibrium
from fmu_src.case import bound_violation
from orchestrator.cli.options import UsageError

#: the models the calculator offers: those that solve the Reynolds equation
FILM_MODELS = tuple(m for m in MODELS if is_film_model(m))


def build_model(name: str, bearing: BearingData, nodes: int | None, pinned_start: bool):
    """A film model from the registry with the CLI's options (passed straight through:
    a model that does not take one says so; ``--nodes`` checked against the model's bounds)."""
    options = {}
    if nodes is not None:
        for opt in model_class(name).options:
            violated = opt.key == "nodes" and bound_violation(nodes, opt.minimum, opt.maximum,
                                                              opt.exclusive_minimum)
            if violated:
                raise UsageError(f"--nodes {nodes}: the {name} model needs {violated[0]} "
                                 f"{violated[1]}")
        options["nodes"] = nodes
    if pinned_start:
        options["pinned_start"] = True
    return model_class(name).from_parameters(bearing, **options)


def dimensionless_report(model, eps: float) -> dict:
    """Force, Sommerfeld number, attitude and matrices at (eps, 0), zero velocity."""
    ff = model.dimensionless(eps, 0.0)
    f = ff.force
    fnorm = float(np.hypot(*f))
    lam = model.bearing.lambda_
    k = -ff.d_position
    c = -ff.d_velocity
    return {
        "model": model.name,
        "l_over_d": lam,
        "eccentricity": eps,
        "force": f.tolist(),
        "force_note": "Fbar = F / (6 mu omega R^2 (R/C)^2), local frame, journal at (eps, 0)",
        "sommerfeld": lam / (3.0 * math.pi * fnorm),
        "attitude_deg": math.degrees(math.atan2(f[1], -f[0])),
        "stiffness": k.tolist(),
        "damping": c.tolist(),
        "stiffness_note": "-dFbar/dxbar (xbar = x/C); load-normalised K C/W = this / |Fbar|",
        "damping_note": "-dFbar/dxbar_dot (xbar_dot = xdot/(C omega)); C C omega/W = this / |Fbar|",
        "stiffness_load_normalised": (k / fnorm).tolist(),
        "damping_load_normalised": (c / fnorm).tolist(),
    }


def dimensional_report(model, speed: float, load) -> dict:
    """Static equilibrium under ``load`` [N] at ``speed`` [rad/s], 8 coefficients in SI."""
    sol = static_equilibrium(model, load, speed)
    b = model.bearing
    wnorm = float(np.hypot(*load))
    return {
        "model": model.name,
        "diameter_m": b.diameter,
        "length_m": b.length,
        "clearance_m": b.clearance,
        "viscosity_Pa_s": b.viscosity,
        "speed_rad_s": speed,
        "load_N": list(map(float, load)),
        "sommerfeld": b.sommerfeld(speed, wnorm) if wnorm > 0 else math.inf,
        "x0_m": sol.x0,
        "y0_m": sol.y0,
        "eccentricity": sol.eccentricity,
        "attitude_deg": sol.attitude_deg,
        "force_N": sol.result.force.tolist(),
        "stiffness_N_per_m": sol.result.stiffness.tolist(),
        "damping_N_s_per_m": sol.result.damping.tolist(),
    }


def _fmt_matrix(m) -> str:
    return "\n".join("    [" + "  ".join(f"{v: .6e}" for v in row) + "]" for row in m)


def _print_report(rep: dict) -> None:
    for key, value in rep.items():
        if key.endswith("_note"):
            continue
        if isinstance(value, list) and value and isinstance(value[0], list):
            note = rep.get(key + "_note", "")
            print(f"{key}:" + (f"  ({note})" if note else ""))
            print(_fmt_matrix(value))
        elif isinstance(value, list):
            print(f"{key}: " + "  ".join(f"{v:.6e}" for v in value))
        elif isinstance(value, float):
            print(f"{key}: {value:.6g}")
        else:
            print(f"{key}: {value}")


def write_pressure_png(model, xbar: float, ybar: float, path: str) -> None:
    """Dimensionless pressure field of the film at (xbar, ybar), zero velocity, as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    theta, xi, p = model.pressure_field(xbar, ybar)
    fig, ax = plt.subplots(figsize=(7, 3.5), constrained_layout=True)
    im = ax.pcolormesh(np.degrees(theta), xi, np.asarray(p).T, shading="auto", cmap="viridis")
    fig.colorbar(im, ax=ax, label="p / [6 mu omega (R/C)^2]")
    ax.set_xlabel("theta [deg]")
    ax.set_ylabel("xi = z/R [-]")
    ax.set_title(f"{model.name}: L/D = {model.bearing.lambda_:.3g}, (xbar, ybar) = "
                 f"({xbar:.3g}, {ybar:.3g})")
    fig.savefig(path, dpi=120)
    plt.close(fig)


def add_parser(sub) -> None:
    p = sub.add_parser(
        "bearing",
        help="journal-bearing calculator (force, Sommerfeld number, 8 coefficients)",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--model", choices=FILM_MODELS, default="hybrid")
    p.add_argument("--l-over-d", type=float, help="L/D [-] (dimensionless form)")
    p.add_argument("--eccentricity", type=float, help="eccentricity ratio e/C in [0, 1)")
    p.add_argument("--diameter", type=float, help="bearing diameter D [m]")
    p.add_argument("--length", type=float, help="bearing length L [m]")
    p.add_argument("--clearance", type=float, help="radial clearance C [m]")
    p.add_argument("--viscosity", type=float, help="dynamic viscosity mu [Pa s]")
    p.add_argument("--speed", type=float, help="shaft speed omega [rad/s]")
    p.add_argument("--load", type=float, help="static load W [N], applied along -y")
    p.add_argument("--nodes", type=int, help="circumferential nodes (hybrid n, fd n_theta)")
    p.add_argument("--pinned-start", action="store_true",
                   help="start the film at the maximum film thickness (Raimondi-Boyd tables)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--pressure-png", metavar="FILE", help="write the pressure field as PNG")
    p.set_defaults(func=run)


def _check_inputs(args) -> bool:
    """The options of one of the two forms, each finite and in its range; True for the
    dimensional form. :class:`UsageError` naming the option and its value otherwise."""
    dimensional = {"--diameter": args.diameter, "--length": args.length,
                   "--clearance": args.clearance, "--viscosity": args.viscosity,
                   "--speed": args.speed, "--load": args.load}
    dimensionless = {"--l-over-d": args.l_over_d, "--eccentricity": args.eccentricity}
    given = {o for o, v in (dimensional | dimensionless).items() if v is not None}
    if given & set(dimensional):
        if given & set(dimensionless):
            extra = sorted(given & set(dimensionless))
            raise UsageError(f"{' and '.join(extra)} {'belongs' if len(extra) == 1 else 'belong'}"
                             f" to the dimensionless form; the dimensional form "
                             f"({', '.join(dimensional)}) finds the eccentricity from the load: "
                             f"give one form")
        missing = [o for o in dimensional if o not in given]
        if missing:
            raise UsageError(f"the dimensional form needs {', '.join(missing)} as well")
        for option, value in dimensional.items():
            if not math.isfinite(value) or (option != "--load" and value <= 0.0):
                raise UsageError(f"{option} {value:g}: must be "
                                 + ("finite" if option == "--load" else "finite and > 0"))
        return True
    if len(given) < 2:
        raise UsageError("give --l-over-d and --eccentricity (the dimensionless form), or "
                         f"{', '.join(dimensional)} (the dimensional form)")
    if not (math.isfinite(args.l_over_d) and args.l_over_d > 0.0):
        raise UsageError(f"--l-over-d {args.l_over_d:g}: must be finite and > 0")
    if not 0.0 <= args.eccentricity < 1.0:
        raise UsageError(f"--eccentricity {args.eccentricity:g}: must be in [0, 1) (the "
                         f"eccentricity ratio e/C; 1 is contact)")
    return False


def run(args) -> int:
    dimensional = _check_inputs(args)
    if args.pressure_png and not Path(args.pressure_png).parent.is_dir():
        raise UsageError(f"--pressure-png {args.pressure_png}: no folder "
                         f"{Path(args.pressure_png).parent}")
    if dimensional:
        bearing = BearingData(args.diameter, args.length, args.clearance, args.viscosity)
        model = build_model(args.model, bearing, args.nodes, args.pinned_start)
        rep = dimensional_report(model, args.speed, (0.0, -args.load))
        xb, yb = rep["x0_m"] / args.clearance, rep["y0_m"] / args.clearance
    else:
        # the dimensionless problem depends on L/D only
        bearing = BearingData(diameter=1.0, length=args.l_over_d, clearance=1e-3, viscosity=1.0)
        model = build_model(args.model, bearing, args.nodes, args.pinned_start)
        rep = dimensionless_report(model, args.eccentricity)
        xb, yb = args.eccentricity, 0.0
    if args.json:
        print(json.dumps(rep))
    else:
        _print_report(rep)
    if args.pressure_png:
        try:
            write_pressure_png(model, xb, yb, args.pressure_png)
        except OSError as exc:
            raise UsageError(f"--pressure-png {args.pressure_png}: cannot write "
                             f"({exc.strerror or exc})") from None
        if not args.json:
            print(f"pressure field written to {args.pressure_png}")
    return 0
