#!/usr/bin/python3
"""Quick-look PNG plots of `glaswave retrieve` (PRODUCT.md section 11, DIR/plots/).

Usage: plot_retrieval.py DIR

Reads DIR/retrieval.nc and writes, each through a temporary name:

  retrieval_estimates.png  one panel per variable (canopy height, cover, PAI, ground
                           elevation), every method's estimate in its own colour against the
                           simulation's truth (`V_true`); for real input, which has no truth,
                           against the mission's algorithm (L2A's RH98 and ground, L2B's cover
                           and PAI). rt's 5-95 % intervals drawn as bars.
  retrieval_fits.png       when rt ran and its input was glaswave's shots.nc: up to four shots
                           (spread over the retrieved PAI) with the measured waveform (less its
                           noise mean) and rt's best fit over it: the table's entry
                           (`rt_best_entry`) placed on its ground (`rt_best_ground_elevation`).

On unreadable inputs it prints one line, "plot_retrieval: error: ...", on stderr and exits with
status 1. Run by `glaswave retrieve --plots` (pipeline/app/plots.cpp).
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import netCDF4  # noqa: E402
import numpy as np  # noqa: E402

METHODS = ["gedi_l2a", "gedi_l2b", "wi", "rt", "atl08", "photon_ratio"]
COLOURS = {"gedi_l2a": "tab:orange", "gedi_l2b": "tab:blue", "wi": "tab:green", "rt": "tab:red",
           "atl08": "tab:purple", "photon_ratio": "tab:brown"}
VARIABLES = [("canopy_height", "canopy height (m)"), ("cover", "cover"), ("pai", "PAI"),
             ("ground_elevation", "ground elevation (m)")]
# Real input's reference per variable: the mission's own algorithm.
REFERENCE = {"canopy_height": "gedi_l2a", "cover": "gedi_l2b", "pai": "gedi_l2b",
             "ground_elevation": "gedi_l2a"}
# ATL08 input's: ATL08's own heights and the photon ratio.
REFERENCE_ATL08 = {"canopy_height": "atl08", "cover": "photon_ratio", "pai": "photon_ratio",
                   "ground_elevation": "atl08"}
MAX_FITS = 4
NOISE_FRACTION = 0.15  # bins at each end for the noise level, as retrieve.cpp takes it


def save(fig, path):
    part = path + ".part"
    try:
        fig.savefig(part, format="png", dpi=110)
        os.replace(part, path)
    finally:
        plt.close(fig)
        if os.path.exists(part):
            os.remove(part)


def read_retrieval(path):
    with netCDF4.Dataset(path) as nc:
        nc.set_auto_mask(False)
        v = {name: np.asarray(var[...]) for name, var in nc.variables.items()
             if var.dimensions == ("shot",)}
        v["attrs"] = {name: nc.getncattr(name) for name in nc.ncattrs()}
    return v


def plot_estimates(r, path):
    simulated = "pai_true" in r
    methods = [m for m in METHODS if f"cover_{m}" in r]
    references = REFERENCE_ATL08 if "cover_photon_ratio" in r else REFERENCE
    fig, axes = plt.subplots(1, len(VARIABLES), figsize=(4.2 * len(VARIABLES), 4.0))
    for ax, (variable, label) in zip(axes, VARIABLES):
        reference = f"{variable}_true" if simulated else f"{variable}_{references[variable]}"
        x = r.get(reference)
        drawn = False
        for m in methods:
            y = r.get(f"{variable}_{m}")
            if x is None or y is None or not np.isfinite(y).any():
                continue
            if not simulated and m == references[variable]:
                continue  # itself against itself
            if variable == "ground_elevation":
                y = y - x  # elevations span the terrain: the difference is what shows
            if m == "rt" and f"{variable}_rt_p05" in r:
                low, high = r[f"{variable}_rt_p05"], r[f"{variable}_rt_p95"]
                if variable == "ground_elevation":
                    low, high = low - x, high - x
                ax.errorbar(x, y, yerr=[np.maximum(y - low, 0), np.maximum(high - y, 0)],
                            fmt="none", ecolor=COLOURS[m], alpha=0.25, lw=0.6)
            ax.scatter(x, y, s=8, color=COLOURS[m], label=m, alpha=0.7, lw=0)
            drawn = True
        if drawn and variable != "ground_elevation":
            finite = x[np.isfinite(x)]
            if finite.size:
                ax.plot([finite.min(), finite.max()], [finite.min(), finite.max()], "k-", lw=0.7)
        if variable == "ground_elevation":
            ax.axhline(0.0, color="k", lw=0.7)
        source = "truth" if simulated else references[variable]
        ax.set_xlabel(f"{label}: {source}")
        ax.set_ylabel("estimate − " + source if variable == "ground_elevation" else "estimate")
        ax.set_title(label)
        ax.grid(alpha=0.3)
        if drawn:
            ax.legend(fontsize=8)
    fig.tight_layout()
    save(fig, path)


def noise_mean(wave):
    """The quieter end's mean (retrieve.cpp's end_noise), the level the methods subtract."""
    n = max(2, len(wave) * 15 // 100)
    return min(float(np.mean(wave[:n])), float(np.mean(wave[-n:])))


def plot_fits(r, out_dir, path):
    inputs = r["attrs"].get("inputs", "").split(",")
    table_path = r["attrs"].get("rt_table")
    if "rt_best_entry" not in r or not table_path or not inputs or not inputs[0]:
        return
    with netCDF4.Dataset(inputs[0]) as nc:
        if "rx_waveform" not in nc.variables:
            return  # a GEDI granule: rt does not run on it
        nc.set_auto_mask(False)
        numbers = np.asarray(nc["shot_number"][...])
        bin0, lastbin = np.asarray(nc["elev_bin0"][...]), np.asarray(nc["elev_lastbin"][...])
        index = {int(n): i for i, n in enumerate(numbers)}
        ok = np.flatnonzero((r["rt_best_entry"] >= 0) & np.isfinite(r["pai_rt"]))
        if ok.size == 0:
            return
        # Shots spread over the retrieved PAI: its lowest, highest and between.
        order = ok[np.argsort(r["pai_rt"][ok])]
        chosen = order[np.unique(np.linspace(0, order.size - 1, min(MAX_FITS, order.size))
                                 .round().astype(int))]
        waves = {int(i): np.asarray(nc["rx_waveform"][index[int(r["shot_number"][i])], 0, :])
                 for i in chosen}
    with netCDF4.Dataset(table_path) as table:
        table.set_auto_mask(False)
        height = np.asarray(table["height"][...])
        entries = {int(i): np.asarray(table["waveform"][int(r["rt_best_entry"][i]), 0, :])
                   for i in chosen}
    fig, axes = plt.subplots(1, len(chosen), figsize=(3.6 * len(chosen), 5.0), squeeze=False)
    for ax, i in zip(axes[0], chosen):
        i = int(i)
        k = index[int(r["shot_number"][i])]
        wave = waves[i]
        elevation = np.linspace(bin0[k], lastbin[k], wave.size)
        ax.plot((wave - noise_mean(wave)) * 1e9, elevation, color="0.2", lw=1.0, label="measured")
        ax.plot(entries[i] * 1e9, height + r["rt_best_ground_elevation"][i], color="tab:red",
                lw=1.2, label=f"rt best fit (entry {int(r['rt_best_entry'][i])})")
        ax.axhline(r["ground_elevation_rt"][i], color="tab:red", ls=":", lw=0.8)
        if "ground_elevation_true" in r:
            ax.axhline(r["ground_elevation_true"][i], color="k", ls="--", lw=0.8,
                       label="true ground")
        # From below the ground to above the tallest canopy retrieved or true.
        tallest = np.nanmax([r.get(f"canopy_height_{m}", np.full(i + 1, np.nan))[i]
                             for m in ("rt", "true", "gedi_l2a")] + [10.0])
        ground = r["rt_best_ground_elevation"][i]
        ax.set_ylim(ground - 15.0, ground + tallest + 8.0)
        title = f"shot {int(r['shot_number'][i])}: PAI {r['pai_rt'][i]:.2f}"
        if "pai_true" in r:
            title += f" (true {r['pai_true'][i]:.2f})"
        ax.set_title(title + f"\nflag {int(r['rt_flag'][i])}, χ²/dof "
                     f"{r['rt_chi2_per_dof'][i]:.2f}", fontsize=9)
        ax.set_xlabel("power (nW)")
        ax.set_ylabel("elevation (m)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    save(fig, path)


def main(argv):
    if len(argv) != 2:
        raise ValueError("usage: plot_retrieval.py DIR")
    out_dir = argv[1]
    r = read_retrieval(os.path.join(out_dir, "retrieval.nc"))
    plots = os.path.join(out_dir, "plots")
    os.makedirs(plots, exist_ok=True)
    plot_estimates(r, os.path.join(plots, "retrieval_estimates.png"))
    plot_fits(r, out_dir, os.path.join(plots, "retrieval_fits.png"))


if __name__ == "__main__":
    try:
        main(sys.argv)
    except (OSError, KeyError, IndexError, TypeError, ValueError, RuntimeError) as e:
        if isinstance(e, OSError) and e.filename and e.strerror:
            message = f"cannot read {os.fsdecode(e.filename)}: {e.strerror}"
        else:
            message = " ".join(str(e).split()) or type(e).__name__
        sys.exit(f"plot_retrieval: error: {message}")
