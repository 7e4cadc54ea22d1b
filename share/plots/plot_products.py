#!/usr/bin/python3
"""Quick-look PNG plots of a glaswave run (PRODUCT.md section 4, DIR/plots/).

Usage: plot_products.py DIR

Reads DIR/shots.nc and DIR/footprints.geojson and writes, each through a temporary name so
that no half-written plot lies under its final name:

  waveforms.png       a dozen good shots' waveforms against elevation, every band, with their
                      canopy and ground parts, the sum of the Gaussians fitted to them (the
                      products' gauss_* variables: nothing is fitted here) and the estimated
                      ground elevation;
  track_profile.png   along track: terrain, signal extent, estimated ground and canopy top,
                      and the true canopy top;
  footprints_map.png  the footprints, coloured by reflectance, over a hillshade of the run's
                      DEM in the DEM's own CRS (the resolved configuration, global attribute
                      `config`, names it), or in longitude and latitude for a synthetic plane
                      or a DEM that can no longer be read;
  photon_cloud.png    when DIR/atl03.h5 is there (ICESat-2): each beam's photons, height against
                      distance along track, coloured by their true class, with ATL08's terrain
                      and canopy top estimates (DIR/atl08.h5) beside the simulation's truth.
 On unreadable inputs it prints one line,
"plot_products: error: ...", on stderr and exits with status 1. Run by `glaswave run`
(pipeline/app/plots.cpp) when output.plots is true.
"""
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import netCDF4  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402

EARTH_RADIUS_M = 6371008.8  # mean radius; plenty for distances along a short track
MAX_PANELS = 12
SIGNAL_FRACTION = 0.01  # signal extent: where the waveform exceeds 1% of its peak
NOISE_FRACTION = 0.15  # bins at each end for the noise level (waveform_metrics.hpp)
SUN_AZIMUTH_DEG, SUN_ALTITUDE_DEG = 315.0, 45.0  # hillshade light, the cartographers' default
MAX_HILLSHADE_CELLS = 1500  # along either side of the map; a bigger window is read decimated
MAX_LABEL_CHARS = 40  # a name from the user's data (a band, a CRS) is cut to this in plot text


def read_shots(path):
    with netCDF4.Dataset(path) as ds:
        ds.set_auto_mask(False)  # fill is NaN already; plain arrays are simpler
        v = {name: ds[name][...] for name in (
            "shot_number", "lat", "lon", "elev", "elev_bin0", "elev_lastbin", "quality_flag",
            "bin_time_ns", "rx_waveform", "rx_waveform_canopy", "rx_waveform_ground",
            "n_peaks", "gauss_amp", "gauss_center_m", "gauss_sigma_ns",
            "ground_elev_est", "canopy_height_est", "canopy_height_true")}
        v["band_name"] = [str(name) for name in ds["band_name"][...]]
        config = ds.getncattr("config") if "config" in ds.ncattrs() else "{}"
    try:
        v["config"] = json.loads(config)
    except ValueError:
        v["config"] = {}
    if not isinstance(v["config"], dict):
        v["config"] = {}
    return v


def bin_elevations(shots, i):
    """Elevation (m) of each bin of shot i: linear from elev_bin0 to elev_lastbin."""
    return np.linspace(shots["elev_bin0"][i], shots["elev_lastbin"][i],
                       shots["rx_waveform"].shape[2])


def plain(text, limit=MAX_LABEL_CHARS):
    """Text from the user's data as matplotlib draws it literally: cut to `limit` characters
    (a 5,000-character band name made the figure fail) and every $ escaped, so that no
    mathtext is parsed ($\\frac{1}{$ made it fail)."""
    text = " ".join(str(text).split())
    if len(text) > limit:
        text = text[:limit - 1] + "\u2026"
    return text.replace("$", r"\$")


def band_label(name):
    return plain(name) + (" nm" if name.isdigit() else "")


def band_labels(shots):
    return [band_label(name) for name in shots["band_name"]]


def power_unit(peak_W):
    return (1e-9, "nW") if peak_W >= 1e-9 else (1e-12, "pW")


def metres_per_ns(shots, i):
    """Elevation step per nanosecond along shot i's profile (c/2 at nadir, less off nadir)."""
    span_ns = shots["bin_time_ns"][-1] - shots["bin_time_ns"][0]
    return (shots["elev_bin0"][i] - shots["elev_lastbin"][i]) / span_ns if span_ns > 0 else np.nan


def noise_level(shots, wave):
    """The level the Gaussians were fitted above: with the detector on, the mean of the
    quieter end of the window, as pipeline/products/waveform_metrics.cpp takes it; else 0."""
    detector = shots["config"].get("detector")
    if not (isinstance(detector, dict) and detector.get("enabled") is True):
        return 0.0
    n = max(2, int(NOISE_FRACTION * len(wave)))
    return min(np.mean(wave[:n]), np.mean(wave[-n:]))


def gaussian_fit(shots, i, band, elev_m):
    """Sum (W) over elev_m of the Gaussians fitted to shot i's band, or None without any."""
    n = max(0, int(shots["n_peaks"][i, band]))
    amp, centre, sigma_ns = (shots[name][i, band, :n]
                             for name in ("gauss_amp", "gauss_center_m", "gauss_sigma_ns"))
    sigma_m = sigma_ns * metres_per_ns(shots, i)
    ok = np.isfinite(amp) & np.isfinite(centre) & (sigma_m > 0)
    if not np.any(ok):
        return None
    parts = amp[ok, None] * np.exp(-0.5 * ((elev_m[None, :] - centre[ok, None])
                                           / sigma_m[ok, None]) ** 2)
    return noise_level(shots, shots["rx_waveform"][i, band]) + parts.sum(axis=0)


def add_gaussian_fit(ax, shots, i, band, elev_m, scale, colour):
    """Draws the sum of the Gaussians fitted to shot i's band, thin over the pale total."""
    fit = gaussian_fit(shots, i, band, elev_m)
    if fit is not None:
        ax.plot(fit / scale, elev_m, color=colour, lw=1.0)


def signal_extent(shots, i, fraction=SIGNAL_FRACTION, band=0):
    """(low, high) elevation (m) where the band's waveform exceeds fraction of its peak."""
    wave = shots["rx_waveform"][i, band]
    if not np.any(wave > 0):
        return np.nan, np.nan
    elev = bin_elevations(shots, i)[wave > fraction * np.nanmax(wave)]
    return elev.min(), elev.max()


def plot_waveforms(shots, path):
    good = np.flatnonzero(shots["quality_flag"] == 1)
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
            add_gaussian_fit(ax, shots, i, band, elev, scale, colour)
        ground = shots["ground_elev_est"][i, 0]
        if np.isfinite(ground):
            ax.axhline(ground, color="k", ls=(0, (4, 3)), lw=0.8)
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
    if len(chosen):
        fig.legend(*waveform_legend(shots), loc="lower center", ncol=len(shots["band_name"]) + 1,
                   fontsize=8, frameon=False)
        bottom = (0.1 + 0.17 * 4) / fig.get_figheight()
    fig.suptitle("Received waveforms: canopy and ground parts, Gaussian fit", fontsize=11)
    fig.tight_layout(rect=(0, bottom, 1, 1))
    save(fig, path)


def waveform_legend(shots):
    """Handles and labels: a column per band (total, canopy, ground, fit), then one for the
    ground estimate, padded to the same rows."""
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    handles, labels = [], []
    for band, name in enumerate(band_labels(shots)):
        colour = colours[band % len(colours)]
        handles += [Line2D([], [], color=colour, lw=2.5, alpha=0.45),
                    Line2D([], [], color=colour, ls="--", lw=1.1),
                    Line2D([], [], color=colour, ls="-.", lw=1.1),
                    Line2D([], [], color=colour, lw=1.0)]
        labels += [f"{name} total", f"{name} canopy", f"{name} ground", f"{name} Gaussian fit"]
    handles += [Line2D([], [], color="k", ls=(0, (4, 3)), lw=0.8)] + [Patch(visible=False)] * 3
    labels += [f"ground estimate, {band_labels(shots)[0]}", "", "", ""]
    return handles, labels


def along_track_km(lat_deg, lon_deg):
    """Cumulative haversine distance (km) between successive footprints."""
    lat, lon = np.radians(lat_deg), np.radians(lon_deg)
    a = (np.sin(np.diff(lat) / 2) ** 2
         + np.cos(lat[:-1]) * np.cos(lat[1:]) * np.sin(np.diff(lon) / 2) ** 2)
    step = 2 * EARTH_RADIUS_M * np.arcsin(np.sqrt(np.clip(a, 0, 1)))
    return np.concatenate(([0.0], np.cumsum(step)))[:len(lat)] / 1000.0


def plot_track_profile(shots, path):
    good = np.flatnonzero((shots["quality_flag"] == 1) & np.isfinite(shots["lat"])
                          & np.isfinite(shots["lon"]))
    dist = along_track_km(shots["lat"][good], shots["lon"][good])
    extent = np.array([signal_extent(shots, i) for i in good]).reshape(-1, 2)
    fig, ax = plt.subplots(figsize=(10, 4.5))
    label = f"signal extent, {band_labels(shots)[0]} (> {SIGNAL_FRACTION:.0%} of peak)"
    ax.fill_between(dist, extent[:, 0], extent[:, 1], color="tab:green", alpha=0.35, lw=0,
                    label=label)
    ax.plot(dist, shots["elev"][good], "k.-", lw=1, ms=4, label="terrain at footprint centre")
    band = band_labels(shots)[0]
    ground = shots["ground_elev_est"][good, 0]
    ax.plot(dist, ground, color="tab:orange", ls="--", lw=1.4, label=f"estimated ground, {band}")
    ax.plot(dist, ground + shots["canopy_height_est"][good, 0], color="darkgreen", ls="--",
            lw=1.2, label=f"estimated canopy top, {band}")
    height = shots["canopy_height_true"][good]
    treed = np.isfinite(height) & (height > 0)
    ax.plot(dist[treed], (shots["elev"][good] + height)[treed], "^", color="darkgreen", ms=4,
            label="true canopy top (simulation)")
    ax.set_xlabel("distance along track (km)")
    ax.set_ylabel("elevation (m)")
    skipped = len(shots["quality_flag"]) - len(good)
    ax.set_title(f"Track profile: {len(good)} shots"
                 + (f" ({skipped} flagged shots skipped)" if skipped else ""))
    ax.grid(alpha=0.3)
    if len(good):  # below the axes, where no terrain can hide under it
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=3, fontsize=9,
                  frameon=False)
    else:
        ax.text(0.5, 0.5, "no shot met the terrain", ha="center", va="center",
                transform=ax.transAxes)
    fig.tight_layout()
    save(fig, path)


def map_band(shots):
    """The band the footprint map shows: 1064 nm, the band GLAS and GEDI range with, where the
    run has it, else the last band."""
    names = list(shots["band_name"])
    return "1064" if "1064" in names else names[-1]


def read_footprints(geojson, band):
    """The footprints' outer rings (lon, lat arrays) and their reflectance in `band` (the
    property `reflectance_<band>`)."""
    polygons, values = [], []
    for feature in geojson["features"]:
        geometry = feature.get("geometry")
        if geometry is None or geometry.get("type") != "Polygon":
            continue  # a flagged shot has no footprint
        polygons.append(np.asarray(geometry["coordinates"][0], dtype=float)[:, :2])
        value = feature["properties"].get("reflectance_" + band)
        values.append(np.nan if value is None else value)
    return polygons, values


def dem_background(config, polygons):
    """The hillshade under the footprints from the run's DEM (terrain.dem of the resolved
    configuration), or None for a synthetic plane or a DEM that cannot be read or drawn (moved
    with the products, no CRS, rotated, not under the footprints): the map then stays in
    longitude and latitude. Nothing here fails the plots."""
    terrain = config.get("terrain")
    dem = terrain.get("dem") if isinstance(terrain, dict) else None
    if not polygons or not isinstance(dem, str) or not dem:
        return None
    band = terrain.get("dem_band", 1)
    try:
        from osgeo import gdal, osr
        gdal.UseExceptions()
        osr.UseExceptions()
        gdal.PushErrorHandler("CPLQuietErrorHandler")
        try:
            return read_hillshade(gdal, osr, dem, band if isinstance(band, int) else 1, polygons)
        finally:
            gdal.PopErrorHandler()
    except Exception:  # noqa: BLE001 - whatever GDAL or the file does, the plain map is drawn
        return None


def read_hillshade(gdal, osr, dem, band_number, polygons):
    dataset = gdal.Open(dem)
    srs = dataset.GetSpatialRef()
    transform = dataset.GetGeoTransform()
    if srs is None or transform[2] != 0 or transform[4] != 0:
        return None
    if srs.IsCompound() and hasattr(srs, "StripVertical"):
        srs.StripVertical()  # the map is horizontal
    lonlat = osr.SpatialReference()
    lonlat.ImportFromEPSG(4326)
    for ref in (lonlat, srs):
        ref.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    to_dem = osr.CoordinateTransformation(lonlat, srs)
    points = np.array(to_dem.TransformPoints(np.concatenate(polygons).tolist()))[:, :2]
    if not np.all(np.isfinite(points)):
        return None
    rings = np.split(points, np.cumsum([len(p) for p in polygons])[:-1])

    # Metres per CRS unit across and along (a degree of longitude shrinks with cos(lat)), for
    # gradients in metres and an equal-metre aspect.
    if srs.IsGeographic():
        mid_lat = np.mean(np.concatenate(polygons)[:, 1])
        metres_per_deg = EARTH_RADIUS_M * math.pi / 180.0
        scale_x, scale_y = metres_per_deg * math.cos(math.radians(mid_lat)), metres_per_deg
    else:
        scale_x = scale_y = srs.GetLinearUnits()

    # A square window (in metres) around the footprints with a margin, so that a track running
    # north-south gets terrain beside it; clipped to the raster.
    low, high = points.min(axis=0), points.max(axis=0)
    centre = (low + high) / 2
    size_m = max((high[0] - low[0]) * scale_x, (high[1] - low[1]) * scale_y)
    half_m = 0.55 * size_m + max(300.0, 0.05 * size_m)
    x_edges = (np.array([centre[0] - half_m / scale_x, centre[0] + half_m / scale_x])
               - transform[0]) / transform[1]
    y_edges = (np.array([centre[1] - half_m / scale_y, centre[1] + half_m / scale_y])
               - transform[3]) / transform[5]
    col0 = max(0, math.floor(x_edges.min()))
    col1 = min(dataset.RasterXSize, math.ceil(x_edges.max()))
    row0 = max(0, math.floor(y_edges.min()))
    row1 = min(dataset.RasterYSize, math.ceil(y_edges.max()))
    if col1 - col0 < 3 or row1 - row0 < 3:
        return None  # the footprints are off the DEM

    step = max(1, math.ceil(max(col1 - col0, row1 - row0) / MAX_HILLSHADE_CELLS))
    width, height = math.ceil((col1 - col0) / step), math.ceil((row1 - row0) / step)
    raster = dataset.GetRasterBand(band_number)
    z = raster.ReadAsArray(col0, row0, col1 - col0, row1 - row0, width, height).astype(float)
    nodata = raster.GetNoDataValue()
    if nodata is not None:
        z[z == nodata] = np.nan
    z = z * (raster.GetScale() or 1.0) + (raster.GetOffset() or 0.0)
    cell_x = transform[1] * (col1 - col0) / width  # signed: a row going south has cell_y < 0
    cell_y = transform[5] * (row1 - row0) / height
    left, top = transform[0] + col0 * transform[1], transform[3] + row0 * transform[5]
    extent = (left, left + width * cell_x, top + height * cell_y, top)
    return {"shade": hillshade(z, cell_x * scale_x, cell_y * scale_y), "extent": extent,
            "rings": rings, "aspect": scale_y / scale_x, "srs": srs}


def hillshade(z, cell_east_m, cell_north_m):
    """Cosine of the angle between the ground's normal and the sun (SUN_AZIMUTH_DEG clockwise
    from north, SUN_ALTITUDE_DEG above the horizon), 0 in its shadow; NaN where z is."""
    d_rows, d_cols = np.gradient(z)
    dz_east, dz_north = d_cols / cell_east_m, d_rows / cell_north_m
    azimuth, altitude = np.radians(SUN_AZIMUTH_DEG), np.radians(SUN_ALTITUDE_DEG)
    sun = (np.sin(azimuth) * np.cos(altitude), np.cos(azimuth) * np.cos(altitude), np.sin(altitude))
    shade = (sun[2] - dz_east * sun[0] - dz_north * sun[1]) / np.sqrt(1 + dz_east ** 2
                                                                     + dz_north ** 2)
    return np.clip(shade, 0.0, 1.0)


def crs_labels(srs):
    """Axis labels and a name for the CRS of the map."""
    authority = srs.GetAuthorityName(None), srs.GetAuthorityCode(None)
    name = srs.GetName() + (f" ({authority[0]}:{authority[1]})" if all(authority) else "")
    if srs.IsGeographic():
        return "longitude (°E)", "latitude (°N)", name
    unit = srs.GetLinearUnitsName()
    unit = "m" if unit in ("metre", "meter", "metres", "meters") else plain(unit)
    return f"easting ({unit})", f"northing ({unit})", name


def plot_footprints_map(geojson, shots, path):
    band = map_band(shots)
    polygons, values = read_footprints(geojson, band)
    background = dem_background(shots["config"], polygons)
    fig, ax = plt.subplots(figsize=(8, 7))
    if polygons:
        if background is not None:  # the map in the DEM's CRS
            cmap = matplotlib.colormaps["gray"].with_extremes(bad=(1, 1, 1, 0))
            ax.imshow(background["shade"], cmap=cmap, vmin=0, vmax=1, extent=background["extent"],
                      origin="upper", interpolation="bilinear")
            polygons = background["rings"]
        cmap = matplotlib.colormaps["viridis"].with_extremes(bad="lightgrey")
        cells = PolyCollection(polygons, cmap=cmap, edgecolors="k", linewidths=0.3)
        cells.set_array(np.ma.masked_invalid(values))
        if np.any(np.isfinite(values)):  # at least 0.01 wide, so a uniform surface reads as one
            low, high = np.nanmin(values), np.nanmax(values)
            mid, half = (low + high) / 2, max((high - low) / 2, 0.005)
            cells.set_clim(mid - half, mid + half)
        ax.add_collection(cells)
        bar = fig.colorbar(cells, ax=ax, shrink=0.8, label=f"reflectance, {band_label(band)} (1)")
        bar.formatter.set_useOffset(False)
        if background is not None:
            x0, x1, y0, y1 = background["extent"]
            ax.set_xlim(min(x0, x1), max(x0, x1))
            ax.set_ylim(min(y0, y1), max(y0, y1))
            ax.set_aspect(background["aspect"], adjustable="box")
        else:
            ax.autoscale_view()
            # Equal metres on both axes: a degree of longitude is cos(lat) degrees of latitude.
            # The limits widen to keep that aspect, so a north-south track gets room beside it.
            mean_lat = np.mean(np.concatenate([p[:, 1] for p in polygons]))
            ax.set_aspect(1.0 / np.cos(np.radians(mean_lat)), adjustable="datalim")
    else:
        ax.text(0.5, 0.5, "no footprint on the terrain", ha="center", va="center")
    ax.ticklabel_format(style="plain", useOffset=False)
    ax.xaxis.set_major_locator(MaxNLocator(5))
    title = f"Footprints (1/e² contour on the terrain), {len(polygons)} shots"
    if background is not None:
        xlabel, ylabel, crs = crs_labels(background["srs"])
        title += (f",\nover a hillshade of the DEM (sun from {SUN_AZIMUTH_DEG:g}° at "
                  f"{SUN_ALTITUDE_DEG:g}°) in its CRS, {plain(crs, 80)}")
        description = f"glaswave footprints over a hillshade of the DEM; CRS {crs}"
    else:
        xlabel, ylabel = "longitude (°E)", "latitude (°N)"
        description = "glaswave footprints; longitude and latitude (WGS 84)"
        ax.grid(alpha=0.3)
        terrain = shots["config"].get("terrain")
        if polygons and isinstance(terrain, dict) and terrain.get("dem"):
            title += "\n(no hillshade: the run's DEM cannot be read or does not cover them)"
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    fig.tight_layout()
    save(fig, path, description)


def save(fig, path, description=None):
    """Writes the PNG under path + ".part", then renames it; description goes into its
    Description text chunk (the map says there in which CRS it is drawn)."""
    part = path + ".part"
    try:
        fig.savefig(part, format="png", dpi=120,
                    metadata={"Description": description} if description else None)
        os.replace(part, path)
    finally:
        plt.close(fig)
        if os.path.exists(part):
            os.remove(part)


PHOTON_CLASSES = [  # glaswave_truth_class: 0 background, 1 ground, 2 canopy, 3 top of canopy
    ("background", "0.6", 2), ("ground", "saddlebrown", 3), ("canopy", "forestgreen", 3),
    ("top of canopy", "limegreen", 3)]
MAX_PHOTON_BEAMS = 3


def read_beam_photons(atl03, beam):
    """A beam's photons: along-track distance (its 20 m segment's start plus dist_ph_along),
    height and true class."""
    geo, heights = atl03[beam]["geolocation"], atl03[beam]["heights"]
    count = geo["segment_ph_cnt"][:].astype(np.int64)
    start = np.repeat(geo["segment_dist_x"][:], count)
    along = start + heights["dist_ph_along"][:]
    return along, heights["h_ph"][:], heights["glaswave_truth_class"][:]


def plot_photon_cloud(atl03_path, atl08_path, path):
    import h5py  # only ICESat-2 runs need it
    with h5py.File(atl03_path, "r") as atl03:
        beams = [b for b in sorted(atl03) if b.startswith("gt")]
        strong = [b for b in beams if atl03[b].attrs.get("atlas_beam_type", b"") in
                  (b"strong", "strong")]
        beams = (strong or beams)[:MAX_PHOTON_BEAMS]
        clouds = {b: read_beam_photons(atl03, b) for b in beams}
    segments = {}
    if os.path.exists(atl08_path):
        with h5py.File(atl08_path, "r") as atl08:
            for b in beams:
                land = atl08[b]["land_segments"]
                read = lambda name: np.where(land[name][:] > 1e37, np.nan, land[name][:])
                segments[b] = {name: read(name) for name in (
                    "terrain/h_te_best_fit", "canopy/h_canopy", "glaswave_truth/h_te",
                    "glaswave_truth/h_canopy")}
                first = atl08[b]["land_segments"]["segment_id_beg"][:]
                segments[b]["centre_m"] = (first - 1) * 20.0 + 50.0
    fig, axes = plt.subplots(len(beams), 1, figsize=(11, 3.6 * len(beams)), squeeze=False)
    for ax, beam in zip(axes[:, 0], beams):
        along, h, truth = clouds[beam]
        for code, (label, colour, size) in enumerate(PHOTON_CLASSES):
            mask = truth == code
            ax.scatter(along[mask] / 1000.0, h[mask], s=size, c=colour, lw=0,
                       label=f"{label} ({mask.sum()})", rasterized=True)
        if beam in segments:
            s = segments[beam]
            x = s["centre_m"] / 1000.0
            ax.plot(x, s["glaswave_truth/h_te"], "k-", lw=1.2, label="terrain (truth)")
            ax.plot(x, s["glaswave_truth/h_te"] + s["glaswave_truth/h_canopy"], "-",
                    color="darkgreen", lw=1.2, label="canopy top (truth)")
            ax.plot(x, s["terrain/h_te_best_fit"], "o--", color="tab:orange", ms=3, lw=1,
                    label="ATL08 h_te_best_fit")
            ax.plot(x, s["terrain/h_te_best_fit"] + s["canopy/h_canopy"], "s--",
                    color="tab:blue", ms=3, lw=1, label="ATL08 terrain + h_canopy")
        ax.set_title(f"{beam}: {len(h)} photons")
        ax.set_xlabel("distance along track (km)")
        ax.set_ylabel("height above WGS84 (m)")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, markerscale=3,
                  frameon=False)
    fig.tight_layout()
    save(fig, path)


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
    plot_footprints_map(geojson, shots, os.path.join(plots, "footprints_map.png"))
    atl03 = os.path.join(out_dir, "atl03.h5")
    if os.path.exists(atl03):
        plot_photon_cloud(atl03, os.path.join(out_dir, "atl08.h5"),
                          os.path.join(plots, "photon_cloud.png"))


if __name__ == "__main__":
    try:
        main(sys.argv)
    except (OSError, KeyError, IndexError, TypeError, ValueError, RuntimeError) as e:
        if isinstance(e, OSError) and e.filename and e.strerror:
            message = f"cannot read {os.fsdecode(e.filename)}: {e.strerror}"
        else:
            message = " ".join(str(e).split()) or type(e).__name__
        sys.exit(f"plot_products: error: {message}")
