#!/usr/bin/env python3
"""Writes the demo's terrain: fractal hills as a GeoTIFF in UTM zone 11N (WGS 84), 10 m cells,
heights above the WGS 84 ellipsoid, under the demo pass (share/demo/demo.json: 40 shots from
34.30 N 118.20 W heading 10 degrees). The hills steepen along the pass, from nearly level ground
at its start to slopes of 35 degrees (over 30 m) at its end, so that its waveforms show what slope does.

The same file every time (a fixed random seed); written under a temporary name and renamed.

    make_demo_dem.py OUT.tif
"""

import os
import sys

import numpy as np
from osgeo import gdal, osr

CELL_M = 10.0
WIDTH, HEIGHT = 900, 1100        # 9 km east-west, 11 km north-south
START_LAT, START_LON = 34.30, -118.20
PASS_LENGTH_M = 40 * 172.0       # along the pass, roughly northward
MAX_SLOPE_DEG = 35.0


def fractal_surface(rng, shape, cell_m):
    """A Gaussian random surface with a power-law spectrum (spectral synthesis): hills a few km
    across with ever smaller ones on them, as real terrain has (spectral exponent 5: the hills, not the pebbles, carry the slope)."""
    ky = np.fft.fftfreq(shape[0], d=cell_m)
    kx = np.fft.rfftfreq(shape[1], d=cell_m)
    k2 = ky[:, None] ** 2 + kx[None, :] ** 2
    k0 = 1.0 / 2000.0                # flattens the spectrum beyond 2 km: hills, not a tilted plateau
    amplitude = (k2 + k0 ** 2) ** (-5.0 / 4.0)
    amplitude[0, 0] = 0.0
    noise = rng.standard_normal(amplitude.shape) + 1j * rng.standard_normal(amplitude.shape)
    surface = np.fft.irfft2(noise * amplitude, s=shape)
    return surface / surface.std()


def slope_deg(heights, cell_m):
    gy, gx = np.gradient(heights, cell_m)
    return np.degrees(np.arctan(np.hypot(gx, gy)))


def main(path):
    gdal.UseExceptions()
    utm = osr.SpatialReference()
    utm.ImportFromEPSG(32611)
    wgs84 = osr.SpatialReference()
    wgs84.ImportFromEPSG(4326)
    wgs84.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    x0, y0, _ = osr.CoordinateTransformation(wgs84, utm).TransformPoint(START_LON, START_LAT)
    west, north = np.floor(x0 - 4000.0), np.floor(y0 + 9000.0)

    rng = np.random.default_rng(2005)
    hills = fractal_surface(rng, (HEIGHT, WIDTH), CELL_M)
    # Steepness grows along the pass: a smooth ramp in northing from 10 % to 100 %.
    northing = north - (np.arange(HEIGHT) + 0.5) * CELL_M
    t = np.clip((northing - y0) / PASS_LENGTH_M, 0.0, 1.0)
    ramp = 0.1 + 0.9 * t * t * (3.0 - 2.0 * t)
    relief = hills * ramp[:, None]
    # Scaled so that the steepest ground of the pass's last part slopes MAX_SLOPE_DEG over 30 m,
    # about what a 70 m footprint sees (the 99.5th percentile: single cells are steeper).
    step = 3
    gy, gx = np.gradient(relief[::step, ::step], step * CELL_M)
    steep = np.hypot(gx, gy)[northing[::step] > y0 + 0.7 * PASS_LENGTH_M, :]
    scale = np.tan(np.radians(MAX_SLOPE_DEG)) / np.percentile(steep, 99.5)
    heights = (1200.0 + scale * relief + 0.02 * (northing - y0)[:, None]).astype(np.float32)

    tmp = path + ".part"
    driver = gdal.GetDriverByName("GTiff")
    dataset = driver.Create(tmp, WIDTH, HEIGHT, 1, gdal.GDT_Float32,
                            options=["COMPRESS=DEFLATE", "PREDICTOR=3", "TILED=YES"])
    dataset.SetGeoTransform((west, CELL_M, 0.0, north, 0.0, -CELL_M))
    dataset.SetSpatialRef(utm)
    band = dataset.GetRasterBand(1)
    band.WriteArray(heights)
    band.SetNoDataValue(-9999.0)
    band.SetDescription("height above the WGS 84 ellipsoid")
    band.SetUnitType("m")
    dataset.SetMetadataItem("TIFFTAG_IMAGEDESCRIPTION",
                            "glaswave demo terrain: fractal hills steepening northward, 0 to 35 degrees")
    dataset = None
    os.replace(tmp, path)
    slopes = slope_deg(heights[::step, ::step].astype(np.float64), step * CELL_M)
    print(f"demo terrain: {path} ({WIDTH} x {HEIGHT} cells of {CELL_M:g} m, heights "
          f"{heights.min():.0f} to {heights.max():.0f} m, slopes over 30 m from 0 to "
          f"{np.percentile(slopes, 99.9):.0f} degrees)")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__.strip().splitlines()[-1].strip())
    main(sys.argv[1])
