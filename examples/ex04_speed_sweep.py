"""Example 4: a three-point speed sweep of the paper's spur case (Fig. 8 in miniature).

Each point is a full coupled run (hybrid bearings, in-process) at another input speed, reduced
to the dynamic tooth load factor R and the peak-to-peak of the bearing forces over its last two
pinion revolutions. ``scheduler="none"`` runs the points one after the other here; without it
they go to a Dask LocalCluster (``orchestrator.sweeps.runner``), or to any cluster by address.
The sweep's figures come back labelled (``res.to_xarray()``: one dimension per varied field and
one for the bearing model); each point's decimated time series stay in its group of the file
(``orchestrator.sweeps.file.read_sweep``).

Run: ``python examples/ex04_speed_sweep.py``
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import orchestrator as gsb
from orchestrator.sweeps.file import read_sweep

SPEEDS = (250.0, 325.0, 400.0)  # rad/s


def main(speeds=SPEEDS, periods: int = 64, scheduler: str | None = "none",
         overrides: dict | None = None) -> list[dict]:
    """One dict per speed; ``overrides``: further case fields for every point."""
    case = gsb.load_case("baguet2010_spur", overrides)
    with tempfile.TemporaryDirectory() as tmp:
        res = gsb.sweep(case, {"drive.speed": list(speeds)}, Path(tmp) / "sweep.h5",
                        periods, bearings=["hybrid"], window="52 periods", scheduler=scheduler,
                        progress=False)
        ds = res.to_xarray().sel(bearing_model="hybrid")
        series = read_sweep(res.path)
    return [{"speed_rad_s": w, "R": float(ds.R.sel(drive_speed=w, mesh="mesh")),
             "force_ptp_N": ds.force_ptp.sel(drive_speed=w).values,
             "mean_mesh_force_N": float(d["mesh_force"].mean()),
             "error": str(ds.error.sel(drive_speed=w).item())}
            for w, d in zip(speeds, series, strict=True)]


if __name__ == "__main__":
    print(f"{'speed [rad/s]':>14} {'R':>7} {'ptp bearing 1 [N]':>18} {'ptp bearing 3 [N]':>18} "
          f"{'mean mesh force [N]':>20}")
    for p in main():
        print(f"{p['speed_rad_s']:14.0f} {p['R']:7.3f} {p['force_ptp_N'][0]:18.0f} "
              f"{p['force_ptp_N'][2]:18.0f} {p['mean_mesh_force_N']:20.1f}")
