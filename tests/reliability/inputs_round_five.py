"""Issue 42's classes left after round four, for tests/reliability/inputs_tried.py (which runs
round_five_inputs with its Trial): --resume over changed inputs, voxel grids' units, layers and
values under the beams, LAS scan angles and CRS units, ICESat-2 beams and granule names, GLAS
record indices, facet materials and trees layers, vegetation under no shot, and messages that
named the wrong thing (a VRT loop, a pixel of 1e-300 degrees, heights of 1e38 m, a pointing
vector of 1e300, a material name Assimp cannot hold)."""

import json
import os
import pathlib
import shutil
import signal
import subprocess
import time

TIMEOUT_S = 20


def killed_run(t, config, out):
    """`run CONFIG` killed once its journal is begun: the journal of an interrupted run."""
    shutil.rmtree(out, ignore_errors=True)
    process = subprocess.Popen([t.glaswave, "run", config, "--quiet", "--threads", "1", "--out",
                                out], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    journal = pathlib.Path(out) / "glaswave.journal"
    deadline = time.monotonic() + TIMEOUT_S
    while time.monotonic() < deadline and process.poll() is None and not (
            journal.exists() and journal.stat().st_size >= 32):
        time.sleep(0.02)
    process.send_signal(signal.SIGKILL)
    process.wait()


def resume_cases(t, out):
    # 1. A crowns file changed between the killed run and its resume (a row added; one byte
    # changed with its time put back): refused naming the file; touched only, it resumes.
    crowns = pathlib.Path(t.write("crowns.csv", "lon,lat,base_m,radius_m,half_height_m\n" +
                                  "".join(f"8.0{i:03d},46.0,5,3,4\n" for i in range(50))))
    config = t.config("resume.json", track__shots=2000, simulation__rays_per_shot=20,
                      canopy={"crowns_file": str(crowns)})
    killed_run(t, config, out)
    text = crowns.read_text()
    crowns.write_text(text + "8.2,46.0,5,3,4\n")
    t.run("42/5. --resume after a row was added to the crowns file", [
        "run", config, "--quiet", "--out", out, "--resume"], expect=2,
        says="crowns.csv: changed since the interrupted run began")
    crowns.write_text(text)
    killed_run(t, config, out)
    stat = crowns.stat()
    crowns.write_text(text.replace("8.0001", "8.0002"))
    os.utime(crowns, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    t.run("42/5. --resume after one byte of the crowns file changed, its time put back", [
        "run", config, "--quiet", "--out", out, "--resume"], expect=2, says="(its content")
    crowns.write_text(text)
    killed_run(t, config, out)
    os.utime(crowns)
    t.run("42/5. --resume after the crowns file was touched (the same bits)", [
        "run", config, "--quiet", "--out", out, "--resume"], expect="ok")
    shutil.rmtree(out, ignore_errors=True)


def voxel_cases(t, out, grid_at):
    """grid_at(name, **changes) writes a grid under the track (netCDF4-python)."""
    def voxels(path, name="voxels.json", **changes):
        return t.config(name, canopy={"voxels": {"file": path}}, **changes)

    import netCDF4
    import numpy

    def energy(folder):
        with netCDF4.Dataset(os.path.join(folder, "shots.nc")) as nc:
            return float(numpy.sum(nc["rx_waveform"][:]))

    metres = out + "-m"
    shutil.rmtree(metres, ignore_errors=True)
    plain = voxels(grid_at("plain.nc"), "plain.json")
    done = subprocess.run([t.glaswave, "run", plain, "--quiet", "--out", metres],
                          capture_output=True)
    reference = energy(metres) if done.returncode == 0 else float("nan")
    for name, changes in [
            ("pad in cm2 cm-3 (values / 100)", {"pad_units": "cm2 cm-3", "pad_scale": 0.01}),
            ("z in cm (x 100)", {"z_units": "cm", "z_scale": 100.0}),
            ("x and y in km over a CRS in metres", {"xy_units": "km"})]:
        path = grid_at(name.split()[0] + "-units.nc", **changes)
        done = t.run(f"42/6. a grid's {name}: the waveforms of the grid in metres", [
            "run", voxels(path), "--quiet", "--out", out], expect="ok")
        # The same scene to a float's rounding: the received energy within 1e-5 of it.
        if done.returncode == 0 and not abs(energy(out) - reference) <= 1e-5 * abs(reference):
            row = list(t.rows[-1])
            row[4] = f"NOT THE GRID IN METRES ({energy(out)} against {reference})"
            t.rows[-1] = tuple(row)
        shutil.rmtree(out, ignore_errors=True)
    shutil.rmtree(metres, ignore_errors=True)
    for name, changes, says in [
            ("pad in 'furlongs'", {"pad_units": "furlong-1"}, "not a plant area density"),
            ("pad in m2 m-2 (an index, not a density)", {"pad_units": "m2 m-2"},
             "not a plant area density"),
            ("z in 'hands'", {"z_units": "hands"}, "not a length glaswave knows"),
            ("layers under the ground (z from -4 m)", {"z_shift": -4.0}, "under the ground"),
            ("repeated z centres within increasing bounds", {"z_centres": (1.0, 1.0, 1.0)},
             "lies outside its bounds")]:
        t.run(f"42/6. a grid's {name}", ["check", voxels(grid_at("bad.nc", **changes))],
              expect=3, says=says)
    nan = voxels(grid_at("nan.nc", nan_under_track=True), "nan.json")
    t.run("42/6. NaN densities under the beams (check)", ["check", nan], expect=3, says="missing")
    t.run("42/6. NaN densities under the beams (run)", ["run", nan, "--quiet", "--out", out],
          out=out, expect=3, says="missing")
    far = voxels(grid_at("plain.nc"), "far.json", track__start_lat_deg=46.1,
                 terrain={"plane": {"origin_lat_deg": 46.1, "origin_lon_deg": 8.0}})
    t.run("42/6. a voxel grid under no shot (11 km away)", ["run", far, "--quiet", "--out", out],
          out=out, expect="ok", says="/canopy/voxels/file: the grid of")


def las_cases(t, out, write_las):
    points = [(500000.5 + i, 4000000.5 + j, 100.0 + (10.0 if (i + j) % 2 else 0.0),
               5 if (i + j) % 2 else 2) for i in range(20) for j in range(20)]
    grid = str(t.path("las-grid.nc"))
    wide = write_las(t.path("wide.las"), points, scan_deg=100)
    t.run("42/7. LAS scan angles of 100 degrees", ["voxelize", wide, "--crs", "EPSG:32633",
          "--out", grid, "--force"], expect=3, says="beyond the LAS specification's -90 to 90")
    plot = write_las(t.path("crs.las"), points)
    t.run("42/7. a cloud in a geographic CRS (EPSG:4326)", [
        "voxelize", plot, "--crs", "EPSG:4326", "--out", grid, "--force"], expect=2,
        says="geographic")
    t.run("42/7. a cloud in US survey feet (EPSG:2263)", [
        "voxelize", plot, "--crs", "EPSG:2263", "--out", grid, "--force"], expect=2,
        says="US survey foot")


def granule_cases(t, out):
    import h5py
    import numpy
    gedi = t.path("beams.h5")
    with h5py.File(gedi, "w") as f:
        for beam in ("BEAM0101", "BEAM2222"):
            # A real GEDI shot number (orbit 8472, beam 0101): past GLAS's 40 x (2^31 - 1).
            f[beam + "/shot_number"] = numpy.array([84720600200035033, 84720600200035034], "u8")
            f[beam + "/lat_lowestmode"] = numpy.array([46.0, 46.0005])
            f[beam + "/lon_lowestmode"] = numpy.array([8.0, 8.0001])
            f[beam + "/delta_time"] = numpy.array([4.0e7, 4.0e7 + 0.0083])
    granule = {"type": "granule", "file": str(gedi), "altitude_m": 420000.0}
    t.run("42/8. a granule's BEAM2222 named in track.beams", ["check", t.config(
        "beam.json", track=dict(granule, beams=["BEAM2222"]))], expect=3, says="the 8 are")
    t.run("42/8. GLAH14 of a GEDI-numbered track (i_rec_ndx past 2^31)", ["check", t.config(
        "glah.json", track=granule, output={"glah14": True})], expect=2,
        says="i_rec_ndx, a 4-byte integer")
    fill = t.path("fill.h5")
    with h5py.File(fill, "w") as f:
        f["BEAM0101/shot_number"] = numpy.array([1, 2], "u8")
        f["BEAM0101/lat_lowestmode"] = numpy.array([46.0, -9999.0])
        f["BEAM0101/lon_lowestmode"] = numpy.array([8.0, -9999.0])
        f["BEAM0101/delta_time"] = numpy.array([4.0e7, 4.0e7 + 0.0083])
    t.run("42/8. a GEDI fill latitude (run warns as check does)", ["run", t.config(
        "fill.json", track={"type": "granule", "file": str(fill), "altitude_m": 420000.0}),
        "--quiet", "--out", out], out=out, expect="ok", says="fill latitude or longitude")
    t.run("42/8. ICESat-2 \"beams\": []", ["check", t.config(
        "nobeam.json", sensor={"preset": "atlas", "beams": []})], expect=2,
        says="/sensor/beams: names no beam")
    t.run("42/8. output.atl03 with the waveform receiver", ["check", t.config(
        "atl03.json", output={"atl03": True})], expect="ok", says="writes no ICESat-2 granule")


def facet_cases(t, out):
    trees = t.write("trees5.csv", "x,y,model,rotation_deg,scale\n0,0,oak,0,1\n")
    # More than 65,535 materials is refused in read_facet_mesh (facet_trees.cpp); the OBJ of
    # 65,536 materials it takes Assimp over 20 s to read on a loaded machine, so it is not here.
    name = "m" * 5000
    t.write("long.mtl", f"newmtl {name}\nKd 0.5 0.5 0.5\n")
    long = t.write("long.obj", f"mtllib long.mtl\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nusemtl {name}\n"
                   "f 1 2 3\n")
    t.run("42/9. a material name of 5,000 characters", ["check", t.config("long.json", canopy={
        "facets": {"trees_file": trees, "models": {"oak": long},
                   "materials": {"leaf": {"reflectance": 0.3}}}})], expect=3,
        says="longer than the 1,023 bytes")
    plate = t.write("plate5.obj", "v -1 -1 1\nv 1 -1 1\nv 1 1 1\nf 1 2 3\n")
    facets = {"models": {"oak": plate}, "materials": {"DefaultMaterial": {"reflectance": 0.3}}}
    layer = t.write("trees.geojson", json.dumps({"type": "FeatureCollection", "features": [{
        "type": "Feature", "geometry": {"type": "Point", "coordinates": [8.0, 46.0]},
        "properties": {"model": "oak", "rotation_deg": "north", "scale": 1}}]}))
    t.run("42/9. a trees layer's rotation_deg 'north'", ["check", t.config(
        "layer.json", canopy={"facets": dict(facets, trees_file=layer)})], expect=3,
        says="rotation_deg is \"north\", not a number")
    far = t.write("far.csv", "lon,lat,model,rotation_deg,scale\n8.0,46.2,oak,0,1\n")
    t.run("42/9. facet trees 22 km from the track", ["check", t.config(
        "far.json", canopy={"facets": dict(facets, trees_file=far)})], expect="ok",
        says="/canopy/facets/trees_file: none of the 1 trees")


def terrain_cases(t):
    from osgeo import gdal, osr
    import numpy
    wgs84 = osr.SpatialReference()
    wgs84.ImportFromEPSG(4326)

    def dem(name, value, pixel=0.0005):
        path = str(t.path(name))
        raster = gdal.GetDriverByName("GTiff").Create(path, 20, 20, 1, gdal.GDT_Float32)
        raster.SetGeoTransform([7.995, pixel, 0, 46.005, 0, -pixel])
        raster.SetSpatialRef(wgs84)
        raster.GetRasterBand(1).WriteArray(numpy.full((20, 20), value, dtype=numpy.float32))
        raster = None
        return t.config(name + ".json", terrain={"dem": path})

    t.run("42/10. a DEM of heights 1e38 m (an undeclared fill)", ["check", dem("fill.tif", 1e38)],
          expect=3, says="no height on the Earth")
    t.run("42/10. a DEM pixel of 1e-300 degrees", ["check", dem("tiny.tif", 900.0, 1e-300)],
          expect=3, says="is its geotransform right?")
    vrt = ('<VRTDataset rasterXSize="20" rasterYSize="20"><SRS>EPSG:4326</SRS><GeoTransform>'
           '7.995,0.0005,0,46.005,0,-0.0005</GeoTransform><VRTRasterBand dataType="Float32" '
           'band="1"><SimpleSource><SourceFilename relativeToVRT="1">{}</SourceFilename>'
           '<SourceBand>1</SourceBand></SimpleSource></VRTRasterBand></VRTDataset>')
    a = t.write("a.vrt", vrt.format("b.vrt"))
    t.write("b.vrt", vrt.format("a.vrt"))
    t.run("42/10. two VRTs sourcing each other", ["check", t.config(
        "vrt.json", terrain={"dem": a})], expect=3, says="a.vrt -> b.vrt -> a.vrt")
    from inputs_tried import ecef
    x, y, z = ecef(46.0, 8.0, 600000.0)
    sx, sy, sz = ecef(46.0, 8.0, 0.0)
    text = "time,x_m,y_m,z_m,pointing_x,pointing_y,pointing_z\n" + \
        f"0,{x},{y},{z},{(sx - x) * 1e294},{(sy - y) * 1e294},{(sz - z) * 1e294}\n"
    t.run("42/10. an ephemeris pointing vector of 1e300", ["check", t.config(
        "pointing.json", track={"type": "ephemeris", "ephemeris": t.write("e.csv", text)})],
        expect="ok")


def grid_writer(t):
    """grid_at(name, ...): a 40 x 40 x 3 grid of 2 m columns about the track's start (46 N, 8 E,
    UTM 32N), written by netCDF4-python in metres, or with the units and values changed."""
    import netCDF4
    import numpy
    from osgeo import osr
    from inputs_tried import GEODETIC
    utm = osr.SpatialReference()
    utm.ImportFromEPSG(32632)
    x_c, y_c, _ = osr.CoordinateTransformation(GEODETIC, utm).TransformPoint(46.0, 8.0, 0.0)

    def grid_at(name, pad_units=None, pad_scale=1.0, z_units=None, z_scale=1.0, xy_units=None,
                z_shift=0.0, z_centres=None, nan_under_track=False):
        path = str(t.path(name))
        xy_scale = 0.001 if xy_units == "km" else 1.0
        with netCDF4.Dataset(path, "w") as nc:
            for d, n in (("z", 3), ("y", 40), ("x", 40), ("nv", 2)):
                nc.createDimension(d, n)
            x = nc.createVariable("x", "f8", ("x",))
            y = nc.createVariable("y", "f8", ("y",))
            x[:] = (x_c - 40 + 2 * numpy.arange(40) + 1) * xy_scale
            y[:] = (y_c - 40 + 2 * numpy.arange(40) + 1) * xy_scale
            if xy_units:
                x.units = y.units = xy_units
            z = nc.createVariable("z", "f8", ("z",))
            z[:] = (numpy.array(z_centres or (1.0, 3.0, 5.0)) + z_shift) * z_scale
            z.bounds = "z_bounds"
            if z_units:
                z.units = z_units
            bounds = nc.createVariable("z_bounds", "f8", ("z", "nv"))
            bounds[:] = (numpy.array([[0, 2], [2, 4], [4, 6]]) + z_shift) * z_scale
            crs = nc.createVariable("crs", "i4")
            crs.crs_wkt = utm.ExportToWkt()
            pad = nc.createVariable("pad", "f4", ("z", "y", "x"))
            pad.grid_mapping = "crs"
            if pad_units:
                pad.units = pad_units
            values = numpy.full((3, 40, 40), 0.25 * pad_scale)
            if nan_under_track:
                values[1, 18:22, 18:22] = numpy.nan
            pad[:] = values
        return path

    return grid_at


def round_five_inputs(t):
    """Issue 42's classes after round four (this file's docstring)."""
    from inputs_tried import write_las
    out = str(t.path("out5"))
    resume_cases(t, out)
    voxel_cases(t, out, grid_writer(t))
    las_cases(t, out, write_las)
    granule_cases(t, out)
    facet_cases(t, out)
    terrain_cases(t)
