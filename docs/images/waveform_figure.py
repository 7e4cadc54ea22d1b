#!/usr/bin/python3
"""The README's and the manual's figure of a waveform and its parts, drawn from a run's shots.nc.

Usage: waveform_figure.py SHOTS_NC OUT_PNG [SHOT] [BAND]

One shot's received waveform (default shot 0, band 1064) against elevation, as GLAS and GEDI
users draw it: the canopy's and the ground's parts (the simulation's truth), the Gaussians the
processing fitted, and what it reads off them: signal begin and end, the ground, the canopy
height. Drawn from the demo (./scripts/demo): docs/images/waveform.png is
  waveform_figure.py out/demo/shots.nc docs/images/waveform.png
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import netCDF4  # noqa: E402
import numpy as np  # noqa: E402

C_M_PER_NS = 0.299792458


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__.strip())
    path, out = sys.argv[1], sys.argv[2]
    shot = int(sys.argv[3]) if len(sys.argv) > 3 else 0
    band_nm = float(sys.argv[4]) if len(sys.argv) > 4 else 1064.0
    with netCDF4.Dataset(path) as ds:
        ds.set_auto_mask(False)
        b = int(np.argmin(np.abs(ds["band"][:] - band_nm)))
        v = {name: ds[name][shot, b] for name in (
            "rx_waveform", "rx_waveform_canopy", "rx_waveform_ground", "sig_begin_m", "sig_end_m",
            "ground_elev_est", "canopy_height_est", "n_peaks", "gauss_amp", "gauss_center_m",
            "gauss_sigma_ns")}
        bin0, last = ds["elev_bin0"][shot], ds["elev_lastbin"][shot]
        bins = ds["rx_waveform"].shape[-1]
    elevation = np.linspace(bin0, last, bins)
    scale = 1e9  # W -> nW
    top = v["sig_begin_m"] + 6.0
    bottom = v["sig_end_m"] - 15.0  # room for the legend below signal end
    keep = (elevation <= top) & (elevation >= bottom)

    fig, ax = plt.subplots(figsize=(5.6, 4.6), dpi=100)
    ax.fill_betweenx(elevation[keep], 0, v["rx_waveform_canopy"][keep] * scale, color="#5aa55a",
                     alpha=0.45, lw=0, label="canopy part (leaves, bark)")
    ax.fill_betweenx(elevation[keep], 0, v["rx_waveform_ground"][keep] * scale, color="#b07a45",
                     alpha=0.45, lw=0, label="ground part")
    ax.plot(v["rx_waveform"][keep] * scale, elevation[keep], color="black", lw=1.4,
            label="received waveform")
    # The fitted Gaussians: their centres are elevations, their widths ns of two-way time.
    for k in range(int(v["n_peaks"])):
        sigma_m = v["gauss_sigma_ns"][k] * C_M_PER_NS / 2.0
        g = v["gauss_amp"][k] * np.exp(-0.5 * ((elevation - v["gauss_center_m"][k]) / sigma_m) ** 2)
        ax.plot(g[keep] * scale, elevation[keep], color="#3060c0", lw=0.9, ls="--",
                label="fitted Gaussians" if k == 0 else None)
    peak = np.nanmax(v["rx_waveform"][keep]) * scale
    for name, value, color in (("signal begin", v["sig_begin_m"], "#c03030"),
                               ("ground (lowest Gaussian)", v["ground_elev_est"], "#804010"),
                               ("signal end", v["sig_end_m"], "#c03030")):
        ax.axhline(value, color=color, lw=0.8, ls=":")
        ax.text(peak * 1.02, value + 0.4, name, color=color, va="bottom", fontsize=8)
    x = peak * 0.78
    ax.annotate("", xy=(x, v["sig_begin_m"]), xytext=(x, v["ground_elev_est"]),
                arrowprops={"arrowstyle": "<->", "color": "#206020"})
    ax.text(x * 1.02, (v["sig_begin_m"] + v["ground_elev_est"]) / 2,
            f"canopy height\n{v['canopy_height_est']:.1f} m", color="#206020", fontsize=8,
            va="center")
    ax.set_xlim(0, peak * 1.55)
    ax.set_ylim(bottom, top)
    ax.set_xlabel("received power (nW)")
    ax.set_ylabel("elevation (m above WGS84)")
    ax.set_title(f"one shot of the demo, {band_nm:.0f} nm", fontsize=10)
    ax.legend(loc="lower right", fontsize=7.5, frameon=False)
    fig.tight_layout()
    fig.savefig(out)


if __name__ == "__main__":
    main()
