"""Example 5: the paper's spur case for 64 mesh periods through the FMUs, and the orbit of
bearing 1 drawn from the result in memory (the Python API only).

Run: ``python examples/ex05_orbit.py`` (writes ``orbit_bearing1.png``)
"""

import matplotlib.pyplot as plt

import orchestrator as gsb


def main(png="orbit_bearing1.png", **options):
    result = gsb.simulate("baguet2010_spur", periods=64, **options)
    orbit = result.to_xarray().journal_position.sel(bearing="1") * 1e6  # µm
    fig, ax = plt.subplots(figsize=(5.5, 5))
    ax.plot(orbit.sel(axis="s"), orbit.sel(axis="t"), lw=0.8)
    ax.set(xlabel="s [µm]", ylabel="t [µm]", aspect="equal",
           title="Journal orbit, bearing 1 (spur case, 64 mesh periods, hybrid)")
    fig.savefig(png, dpi=120, bbox_inches="tight")
    return result


if __name__ == "__main__":
    main()
