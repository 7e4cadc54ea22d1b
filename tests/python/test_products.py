"""shots.nc as a GEDI or GLAS user's tools read it: bands selected by wavelength, parts of a track
combined by coordinates into the whole, GEDI's quality flag with its reason, the grid mapping,
and ACDD's discovery attributes equal to the bounds of the data."""

import importlib.util
import json

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from conftest import assert_datasets_identical, run_command, small_config

# open_mfdataset's own defaults, spelled out for combine_by_coords where dask is missing.
MFDATASET_DEFAULTS = dict(data_vars="all", coords="different", compat="no_conflicts",
                          join="outer", combine_attrs="override")


def test_a_band_is_selected_by_its_wavelength(write_config, tmp_path):
    ds = run_command(write_config(small_config()), tmp_path / "out")
    assert list(ds["band"].values) == [532.0, 1064.0]
    assert ds["band"].attrs["units"] == "nm"
    infrared = ds.sel(band=1064)
    assert infrared["rx_waveform"].dims == ("shot", "bin")
    np.testing.assert_array_equal(infrared["rx_waveform"].values,
                                  ds["rx_waveform"].values[:, 1, :])
    assert str(infrared["band_name"].values) == "1064"


def test_parts_of_a_track_combine_by_coordinates_into_the_whole(write_config, tmp_path):
    path = write_config(small_config(shots=5, rays=200))
    whole = run_command(path, tmp_path / "whole")
    run_command(path, tmp_path / "a", "--shots", "0:2")
    run_command(path, tmp_path / "b", "--shots", "2:5")
    files = [tmp_path / "b" / "shots.nc", tmp_path / "a" / "shots.nc"]  # any order
    assert list(whole["shot"].values) == [0, 1, 2, 3, 4]

    parts = [xr.load_dataset(f) for f in files]
    combined = xr.combine_by_coords(parts, **MFDATASET_DEFAULTS)
    assert_datasets_identical(combined, whole, global_attributes=False)
    if importlib.util.find_spec("dask") is not None:
        with xr.open_mfdataset(files, combine="by_coords") as opened:
            assert_datasets_identical(opened.load(), whole, global_attributes=False)


def write_dem_with_a_hole(path):
    """A UTM plane at 700 m rising 5 cm per metre north, with a nodata hole of 60 m radius
    172*3 m north of the track's start and nothing beyond 1400 m north of it."""
    gdal = pytest.importorskip("osgeo.gdal")
    osr = pytest.importorskip("osgeo.osr")
    x0, y0 = 384409.0, 3799134.0  # near 34.33 N, 118.25 W in UTM 11N
    cell, width, height = 40.0, 40, 45
    left, top = x0 - 800.0, y0 + 1400.0
    cx = left + (np.arange(width) + 0.5) * cell
    cy = top - (np.arange(height) + 0.5) * cell
    xx, yy = np.meshgrid(cx, cy)
    values = 700.0 + 0.05 * (yy - y0)
    values[np.hypot(xx - x0, yy - (y0 + 3 * 172.0)) < 60.0] = -9999.0
    raster = gdal.GetDriverByName("GTiff").Create(str(path), width, height, 1, gdal.GDT_Float64)
    raster.SetGeoTransform([left, cell, 0.0, top, 0.0, -cell])
    srs = osr.SpatialReference()
    srs.ImportFromEPSG(32611)
    raster.SetProjection(srs.ExportToWkt())
    band = raster.GetRasterBand(1)
    band.SetNoDataValue(-9999.0)
    band.WriteArray(values)
    raster = None
    wgs84 = osr.SpatialReference()
    wgs84.ImportFromEPSG(4326)
    wgs84.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    lon, lat, _ = osr.CoordinateTransformation(srs, wgs84).TransformPoint(x0, y0)
    return lat, lon


def test_quality_flag_is_gedis_and_the_reason_says_why(write_config, tmp_path):
    lat, lon = write_dem_with_a_hole(tmp_path / "holes.tif")
    config = small_config(shots=10, rays=300)
    config["terrain"] = {"dem": str(tmp_path / "holes.tif")}
    config["track"].update(start_lat_deg=lat, start_lon_deg=lon, heading_deg=0.0)
    ds = run_command(write_config(config), tmp_path / "out")

    flag, reason = ds["quality_flag"], ds["quality_reason"]
    assert list(flag.attrs["flag_values"]) == [0, 1]
    assert flag.attrs["flag_meanings"].split() == ["not_valid", "valid"]
    assert list(reason.attrs["flag_values"]) == [0, 1, 2, 3, 4]
    assert reason.attrs["flag_meanings"].split() == [
        "none", "off_terrain", "nodata", "no_signal", "low_signal"]
    # The hole's centre (shot 3) and past the raster (9): no terrain on the beam's axis; shot 8
    # has the raster's edge under its beam.
    assert list(flag.values) == [1, 1, 1, 0, 1, 1, 1, 1, 0, 0]
    assert list(reason.values) == [0, 0, 0, 1, 0, 0, 0, 0, 2, 1]
    # A GEDI user's filter keeps exactly the shots with a waveform.
    valid = ds.where(ds["quality_flag"] == 1, drop=True)
    assert valid.sizes["shot"] == 7
    assert np.all(np.isfinite(valid["rx_energy"].values))
    assert np.all(np.isnan(ds["rx_energy"].values[flag.values == 0]))


def test_geolocation_names_its_crs_and_discovery_attributes_bound_the_data(write_config,
                                                                          tmp_path):
    ds = run_command(write_config(small_config(shots=4, rays=200)), tmp_path / "out")
    crs = ds["crs"]
    assert crs.attrs["grid_mapping_name"] == "latitude_longitude"
    assert "WGS 84" in crs.attrs["crs_wkt"] and "ellipsoidal,3" in crs.attrs["crs_wkt"]
    assert crs.attrs["semi_major_axis"] == 6378137.0
    for name in ("elev", "rx_waveform", "rh", "energy_tr", "quality_flag"):
        assert ds[name].attrs["grid_mapping"] == "crs", name
    for name, standard_name in (("lat", "latitude"), ("lon", "longitude"), ("time", "time"),
                                ("elev", "height_above_reference_ellipsoid")):
        assert ds[name].attrs["standard_name"] == standard_name, name

    attrs = ds.attrs
    assert attrs["Conventions"] == "CF-1.10, ACDD-1.3"
    for name in ("title", "summary", "keywords", "date_created"):
        assert attrs[name], name
    assert "creator_name" in attrs
    assert attrs["geospatial_lat_min"] == float(ds["lat"].min())
    assert attrs["geospatial_lat_max"] == float(ds["lat"].max())
    assert attrs["geospatial_lon_min"] == float(ds["lon"].min())
    assert attrs["geospatial_lon_max"] == float(ds["lon"].max())
    # xarray's decoded times, to the microsecond the attributes keep.
    for name, value in (("time_coverage_start", ds["time"].values.min()),
                        ("time_coverage_end", ds["time"].values.max())):
        stated = pd.Timestamp(attrs[name]).tz_localize(None)
        assert abs(stated - pd.Timestamp(value)) <= pd.Timedelta(microseconds=1), name
    # The configuration is still there, whole.
    assert json.loads(attrs["config"])["seed"] == 3
