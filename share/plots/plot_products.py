#!/usr/bin/python3
"""Quick-look PNG plots of a glaswave run (PRODUCT.md section 4, DIR/plots/).

Usage: plot_products.py DIR

Reads DIR/shots.nc and DIR/footprints.geojson and writes DIR/plots/waveforms.png,
track_profile.png and footprints_map.png, each through a temporary name so that no
half-written plot lies under its final name. On unreadable inputs it prints one line,
"plot_products: error: ...", on stderr and exits with status 1. Run by `glaswave run`
(pipeline/app/plots.cpp) when output.plots is true.
"""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import netCDF4  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402

EARTH_RADIUS_M = 6371008.8  # mean radius; plenty for distances along a short track
MAX_PANELS = 12
SIGNAL_FRACTION = 0.01  # signal extent: where the waveform exceeds 1% of its peak


def read_shots(path):
    with netCDF4.Dataset(path) as ds:
        ds.set_auto_mask(False)  # fill is NaN already; plain arrays are simpler
        v = {name: ds[name][...] for name in (
            "shot_number", "lat", "lon", "elev", "elev_bin0", "elev_lastbin", "quality_flag",
            "rx_waveform", "rx_waveform_canopy", "rx_waveform_ground")}
        v["band_name"] = [str(name) for name in ds["band_name"][...]]
    return v


def bin_elevations(shots, i):
    """Elevation (m) of each bin of shot i: linear from elev_bin0 to elev_lastbin."""
    return np.linspace(shots["elev_bin0"][i], shots["elev_lastbin"][i],
                       shots["rx_waveform"].shape[2])


def band_labels(shots):
    return [name + (" nm" if name.isdigit() else "") for name in shots["band_name"]]


def power_unit(peak_W):
    return (1e-9, "nW") if peak_W >= 1e-9 else (1e-12, "pW")


def add_gaussian_fit(ax, elev_m, waveform_W, scale):
    """Hook for the Gaussian decomposition of the waveform (a later issue): nothing yet."""


def signal_extent(shots, i, fraction=SIGNAL_FRACTION, band=0):
    """(low, high) elevation (m) where the band's waveform exceeds fraction of its peak."""
    wave = shots["rx_waveform"][i, band]
    if not np.any(wave > 0):
        return np.nan, np.nan
    elev = bin_elevations(shots, i)[wave > fraction * np.nanmax(wave)]
    return elev.min(), elev.max()


def plot_waveforms(shots, path):
    good = np.flatnonzero(shots["quality_flag"] == 0)
    chosen = good[np.unique(np.linspace(0, len(good) - 1, min(MAX_PANELS, len(good))).round()
                            .astype(int))] if len(good) else []
    ncols = max(1, min(4, len(chosen)))
    nrows = max(1, -(-len(chosen) // ncols))
    fig, axes = plt.subplots(nrows, ncols, figsize=(max(6.4, 3.2 * ncols), 3.6 * nrows), squeeze=False)
    scale, unit = power_unit(np.nanmax(shots["rx_waveform"][chosen]) if len(chosen) else 0.0)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax in axes.flat[len(chosen):]:
        ax.set_axis_off()
    if not len(chosen):
        axes[0, 0].text(0.5, 0.5, "no shot met the terrain", ha="center", va="center")
    for ax, i in zip(axes.flat, chosen):
        elev = bin_elevations(shots, i)
        for band, name in enumerate(band_labels(shots)):
            colour = colours[band % len(colours)]
            wave = shots["rx_waveform"][i, band]
            # The total drawn wide and pale, so a part that equals it still shows on top.
            ax.plot(wave / scale, elev, color=colour, lw=2.5, alpha=0.45, label=f"{name} total")
            for part, style in (("canopy", "--"), ("ground", "-.")):
                values = shots["rx_waveform_" + part][i, band]
                ax.plot(np.where(values > 0, values, np.nan) / scale, elev, color=colour,
                        ls=style, lw=1.1, label=f"{name} {part}")
            add_gaussian_fit(ax, elev, wave, scale)
        # Zoom on the return: the window is usually much longer than the signal.
        extents = np.array([signal_extent(shots, i, 1e-3, b)
                            for b in range(len(shots["band_name"]))])
        extents = extents[np.isfinite(extents[:, 0])]
        if len(extents):
            lo, hi = extents[:, 0].min(), extents[:, 1].max()
            pad = max(5.0, 0.25 * (hi - lo))
            ax.set_ylim(max(lo - pad, elev.min()), min(hi + pad, elev.max()))
        ax.set_xlim(left=0)
        ax.set_title(f"shot {shots['shot_number'][i]}", fontsize=10)
        ax.grid(alpha=0.3)
    for ax in axes[-1, :]:
        ax.set_xlabel(f"received power ({unit})")
    for ax in axes[:, 0]:
        ax.set_ylabel("elevation (m)")
    bottom = 0.0
    if len(chosen):  # one column per band, filled top to bottom: total, canopy, ground
        handles, labels = axes.flat[0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="lower center", ncol=len(shots["band_name"]),
                   fontsize=8, frameon=False)
        bottom = (0.1 + 0.17 * 3) / fig.get_figheight()
    fig.suptitle("Received waveforms (canopy and ground parts dashed)")
    fig.tight_layout(rect=(0, bottom, 1, 1))
    save(fig, path)


def along_track_km(lat_deg, lon_deg):
    """Cumulative haversine distance (km) between successive footprints."""
    lat, lon = np.radians(lat_deg), np.radians(lon_deg)
    a = (np.sin(np.diff(lat) / 2) ** 2
         + np.cos(lat[:-1]) * np.cos(lat[1:]) * np.sin(np.diff(lon) / 2) ** 2)
    step = 2 * EARTH_RADIUS_M * np.arcsin(np.sqrt(np.clip(a, 0, 1)))
    return np.concatenate(([0.0], np.cumsum(step)))[:len(lat)] / 1000.0


def plot_track_profile(shots, path):
    good = np.flatnonzero((shots["quality_flag"] == 0) & np.isfinite(shots["lat"])
                          & np.isfinite(shots["lon"]))
    dist = along_track_km(shots["lat"][good], shots["lon"][good])
    extent = np.array([signal_extent(shots, i) for i in good]).reshape(-1, 2)
    fig, ax = plt.subplots(figsize=(10, 4.5))
    label = f"signal extent, {band_labels(shots)[0]} (> {SIGNAL_FRACTION:.0%} of peak)"
    ax.fill_between(dist, extent[:, 0], extent[:, 1], color="tab:green", alpha=0.35, lw=0,
                    label=label)
    ax.plot(dist, shots["elev"][good], "k.-", lw=1, ms=4, label="terrain at footprint centre")
    ax.set_xlabel("distance along track (km)")
    ax.set_ylabel("elevation (m)")
    skipped = len(shots["quality_flag"]) - len(good)
    ax.set_title(f"Track profile: {len(good)} shots"
                 + (f" ({skipped} flagged shots skipped)" if skipped else ""))
    ax.grid(alpha=0.3)
    if len(good):  # below the axes, where no terrain can hide under it
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2, fontsize=9,
                  frameon=False)
    else:
        ax.text(0.5, 0.5, "no shot met the terrain", ha="center", va="center",
                transform=ax.transAxes)
    fig.tight_layout()
    save(fig, path)


def plot_footprints_map(geojson, path):
    polygons, values = [], []
    for feature in geojson["features"]:
        geometry = feature.get("geometry")
        if geometry is None or geometry.get("type") != "Polygon":
            continue  # a flagged shot has no footprint
        polygons.append(np.asarray(geometry["coordinates"][0], dtype=float))
        value = feature["properties"].get("reflectance")
        values.append(np.nan if value is None else value)
    fig, ax = plt.subplots(figsize=(8, 7))
    if polygons:
        cmap = matplotlib.colormaps["viridis"].with_extremes(bad="lightgrey")
        cells = PolyCollection(polygons, cmap=cmap, edgecolors="k", linewidths=0.3)
        cells.set_array(np.ma.masked_invalid(values))
        if np.any(np.isfinite(values)):  # at least 0.01 wide, so a uniform surface reads as one
            low, high = np.nanmin(values), np.nanmax(values)
            mid, half = (low + high) / 2, max((high - low) / 2, 0.005)
            cells.set_clim(mid - half, mid + half)
        ax.add_collection(cells)
        ax.autoscale_view()
        bar = fig.colorbar(cells, ax=ax, shrink=0.8, label="reflectance, first band (1)")
        bar.formatter.set_useOffset(False)
        # Equal metres on both axes: a degree of longitude is cos(lat) degrees of latitude.
        # The limits widen to keep that aspect, so a north-south track gets room beside it.
        mean_lat = np.mean(np.concatenate([p[:, 1] for p in polygons]))
        ax.set_aspect(1.0 / np.cos(np.radians(mean_lat)), adjustable="datalim")
    else:
        ax.text(0.5, 0.5, "no footprint on the terrain", ha="center", va="center")
    ax.ticklabel_format(useOffset=False)
    ax.xaxis.set_major_locator(MaxNLocator(5))
    ax.set_xlabel("longitude (°E)")
    ax.set_ylabel("latitude (°N)")
    ax.set_title(f"Footprints (1/e² contour on the terrain), {len(polygons)} shots")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    save(fig, path)


def save(fig, path):
    part = path + ".part"
    try:
        fig.savefig(part, format="png", dpi=120)
        os.replace(part, path)
    finally:
        plt.close(fig)
        if os.path.exists(part):
            os.remove(part)


def main(argv):
    if len(argv) != 2:
        raise ValueError("usage: plot_products.py DIR")
    out_dir = argv[1]
    shots = read_shots(os.path.join(out_dir, "shots.nc"))
    with open(os.path.join(out_dir, "footprints.geojson"), encoding="utf-8") as f:
        geojson = json.load(f)
    plots = os.path.join(out_dir, "plots")
    os.makedirs(plots, exist_ok=True)
    plot_waveforms(shots, os.path.join(plots, "waveforms.png"))
    plot_track_profile(shots, os.path.join(plots, "track_profile.png"))
    plot_footprints_map(geojson, os.path.join(plots, "footprints_map.png"))


if __name__ == "__main__":
    try:
        main(sys.argv)
    except (OSError, KeyError, IndexError, TypeError, ValueError, RuntimeError) as e:
        if isinstance(e, OSError) and e.filename and e.strerror:
            message = f"cannot read {os.fsdecode(e.filename)}: {e.strerror}"
        else:
            message = " ".join(str(e).split()) or type(e).__name__
        sys.exit(f"plot_products: error: {message}")
