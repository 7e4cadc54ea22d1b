#!/usr/bin/python3
"""Writes the seed corpus of the fuzz targets into tests/fuzz/corpus/<target>/: a few valid
inputs and a few broken ones per target, small, made by hand here (the DEMs with GDAL's Python
bindings, python3-gdal). Regression inputs found by fuzzing live beside them, named
regression-*, and are not touched. Run from anywhere: /usr/bin/python3 tests/fuzz/make_corpus.py
"""
import json
import pathlib
import random

from osgeo import gdal, osr

HERE = pathlib.Path(__file__).resolve().parent / "corpus"


def write(target, name, content):
    folder = HERE / target
    folder.mkdir(parents=True, exist_ok=True)
    data = content if isinstance(content, bytes) else content.encode()
    (folder / name).write_bytes(data)


# WGS 84 latitude, longitude and height to Earth-fixed x, y, z (m), through PROJ.
GEODETIC, GEOCENTRIC = osr.SpatialReference(), osr.SpatialReference()
GEODETIC.ImportFromEPSG(4979)
GEOCENTRIC.ImportFromEPSG(4978)
ecef = osr.CoordinateTransformation(GEODETIC, GEOCENTRIC).TransformPoint


def config_corpus():
    demo = json.loads((HERE.parent.parent.parent / "share/demo/demo.json").read_text())
    write("config", "demo.json", json.dumps(demo, indent=1))
    write("config", "empty.json", "{}")
    write("config", "plane.json", json.dumps({
        "terrain": {"plane": {"origin_lat_deg": 45, "slope_deg": 10, "aspect_deg": 90},
                    "roughness": {"rms_m": 0.45, "correlation_m": 0.5}},
        "canopy": None, "simulation": {"rays_per_shot": 500, "max_order": 2}}))
    write("config", "stands.json", json.dumps({
        "terrain": {"dem": "dem.tif", "vertical_datum": "egm96"},
        "canopy": {"pai": 2, "crown_shape": "cone", "stands": "stands.geojson"},
        "output": {"footprints_format": "GPKG", "plots": False}}))
    write("config", "ephemeris.json", json.dumps({
        "sensor": {"preset": "gedi", "bins": 1000}, "terrain": {"plane": {"elevation_m": 200}},
        "track": {"type": "ephemeris", "ephemeris": "eph.csv"},
        "detector": {"enabled": True, "bits": 8, "saturation_W": 1e-6, "photon_noise": True}}))
    write("config", "points.json", json.dumps({
        "seed": 7, "terrain": {"plane": {}}, "track": {"type": "points", "points": [{"lat_deg": 1, "lon_deg": 2}]},
        "brf": {"views": [{"zenith_deg": 10, "azimuth_deg": 5}]}}))
    write("config", "broken-truncated.json", '{"canopy": {"pai": 3, "lad": "sph')
    write("config", "broken-types.json", '{"seed": "one", "sensor": [], "canopy": {"pai": -1}}')
    write("config", "broken-unknown.json", '{"canopi": {}, "track": {"type": "orbitt"}}')
    write("config", "broken-numbers.json", '{"seed": 1e999, "simulation": {"rays_per_shot": 0x10}}')


def csv_corpus():
    write("csv", "crowns-xy.csv", "x,y,base_m,radius_m,half_height_m\n# one tree\n0,0,5,8,8\n"
          "12.5, -3 ,4,2.5,3\r\n")
    write("csv", "crowns-lonlat.csv", "lon,lat,base_m,radius_m,half_height_m\n7.0,45.0,5,3,4\n")
    write("csv", "numbers.csv", "a,b,c\n+1,-2.5e3,  0x10 \n1e308,1e309,nan\n,,\n#x\n\n")
    write("csv", "broken-crowns.csv", "lon,lat,base_m,radius_m\n0,0,5,eight,8\n1,2\n")
    write("csv", "broken-binary.csv", bytes(range(256)))


def ephemeris_corpus():
    rows = ["# ICESat-like shots", "time,x_m,y_m,z_m"]
    for i in range(3):
        rows.append("%.3f,%.4f,%.4f,%.4f" % ((183124800.0 + 0.025 * i,) + ecef(45 + 0.0015 * i, 7,
                                                                                   600000)))
    write("ephemeris", "positions.csv", "\n".join(rows) + "\n")
    x, y, z = ecef(-30, 150, 500000)
    write("ephemeris", "pointing.csv",
          "x_m, y_m, z_m, time, pointing_x, pointing_y, pointing_z\r\n\n"
          "%.4f,%.4f,%.4f,2005-10-21T12:00:00.025Z,%.6f,%.6f,%.6f\n" % (x, y, z, -x, -y, -z))
    write("ephemeris", "broken-header.csv", "time,x_m,y_m\n1,2,3\n")
    write("ephemeris", "broken-underground.csv", "time,x_m,y_m,z_m\n0,1,2,3\n")
    write("ephemeris", "broken-pointing.csv",
          "time,x_m,y_m,z_m,pointing_x,pointing_y,pointing_z\n"
          "2005-13-40T25:61:61Z,7000000,0,0,0,0,0\n")


def feature(ring, **properties):
    return {"type": "Feature", "properties": properties,
            "geometry": {"type": "Polygon", "coordinates": [ring]}}


def stands_corpus():
    square = [[7, 45], [7.001, 45], [7.001, 45.001], [7, 45.001], [7, 45]]
    write("stands", "two-stands.geojson", json.dumps({"type": "FeatureCollection", "features": [
        feature(square, pai=1.5, crown_shape="cone"),
        feature([[x + 0.002, y] for x, y in square], cover=0.3,
                leaf_reflectance='{"532": 0.1, "1064": 0.4}')]}))
    write("stands", "multipolygon.geojson", json.dumps({"type": "FeatureCollection", "features": [{
        "type": "Feature", "properties": {},
        "geometry": {"type": "MultiPolygon", "coordinates": [[square], [[[x, y + 0.01]
                                                                          for x, y in square]]]}}],
        "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:OGC:1.3:CRS84"}}}))
    write("stands", "utm.geojson", json.dumps({"type": "FeatureCollection", "crs": {
        "type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32632"}}, "features": [
        feature([[500000, 5000000], [500100, 5000000], [500100, 5000100], [500000, 5000000]])]}))
    write("stands", "empty.geojson", '{"type": "FeatureCollection", "features": []}')
    write("stands", "broken-point.geojson", json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {}, "geometry": {"type": "Point",
                                                           "coordinates": [1, 2]}}]}))
    write("stands", "broken-ring.geojson", json.dumps({"type": "FeatureCollection", "features": [
        feature([[0, 0], [1, 1], [0, 0]], pai=-3)]}))
    write("stands", "broken-lonlat.geojson", json.dumps({"type": "FeatureCollection", "features": [
        feature([[500, 45], [501, 45], [501, 46], [500, 45]], crown_shape="layer")]}))


def dem_corpus():
    gdal.UseExceptions()
    driver = gdal.GetDriverByName("GTiff")
    made = []

    def make(name, epsg, transform, kind=gdal.GDT_Float32, nodata=None, bands=1, size=(6, 5)):
        path = "/vsimem/" + name
        dataset = driver.Create(path, size[0], size[1], bands, kind)
        dataset.SetGeoTransform(transform)
        if epsg:
            srs = osr.SpatialReference()
            srs.SetFromUserInput(epsg)
            dataset.SetSpatialRef(srs)
        for b in range(1, bands + 1):
            band = dataset.GetRasterBand(b)
            if nodata is not None:
                band.SetNoDataValue(nodata)
            values = [[100 + 3 * i + 2 * j for i in range(size[0])] for j in range(size[1])]
            if nodata is not None:
                values[1][1] = nodata
            band.WriteRaster(0, 0, size[0], size[1],
                             b"".join(gdal_pack(kind, v) for row in values for v in row))
        dataset = None
        f = gdal.VSIFOpenL(path, "rb")
        gdal.VSIFSeekL(f, 0, 2)
        length = gdal.VSIFTellL(f)
        gdal.VSIFSeekL(f, 0, 0)
        data = bytes(gdal.VSIFReadL(1, length, f))
        gdal.VSIFCloseL(f)
        gdal.Unlink(path)
        write("dem", name, data)
        made.append(data)

    make("geographic.tif", "EPSG:4326", (7.0, 0.001, 0, 45.0, 0, -0.001))
    make("utm-nodata.tif", "EPSG:32632", (500000, 30, 0, 5000000, 0, -30), nodata=-9999)
    make("egm96-int16.tif", "EPSG:4326+5773", (-118.2, 0.0003, 0, 34.3, 0, -0.0003),
         kind=gdal.GDT_Int16)
    make("two-bands.tif", "EPSG:3857", (0, 10, 0, 0, 0, -10), bands=2)
    make("broken-no-crs.tif", None, (0, 1, 0, 0, 0, -1))
    write("dem", "broken-truncated.tif", made[0][: len(made[0]) // 2])
    # VRTs, read beside the target's dem.tif, fifo (a FIFO nobody writes) and inner.vrt (whose
    # source is the FIFO): each source that is no regular file is refused before GDAL opens it.
    def vrt(source, relative=1):
        return ('<VRTDataset rasterXSize="4" rasterYSize="4"><SRS>EPSG:4326</SRS>'
                '<GeoTransform>7, 0.001, 0, 45, 0, -0.001</GeoTransform>'
                '<VRTRasterBand dataType="Float32" band="1"><SimpleSource>'
                f'<SourceFilename relativeToVRT="{relative}">{source}</SourceFilename>'
                '<SourceBand>1</SourceBand></SimpleSource></VRTRasterBand></VRTDataset>')
    write("dem", "vrt-of-tiff.vrt", vrt("dem.tif"))
    write("dem", "broken-vrt-of-fifo.vrt", vrt("fifo"))
    write("dem", "broken-vrt-of-vrt-of-fifo.vrt", vrt("inner.vrt"))
    write("dem", "broken-vrt-of-vsistdin.vrt", vrt("/vsistdin/", 0))
    # Inputs that are not TIFFs describe a raster to the target (FuzzedDataProvider).
    rng = random.Random(13)
    for i in range(4):
        write("dem", "described-%d" % i, bytes(rng.randrange(256) for _ in range(400)))


def granule_corpus():
    """Small GEDI L2A and GLAH14 granules, whole and cut, and with the faults issue 28 found."""
    import io
    import h5py
    import numpy as np

    def h5(name, fill):
        buffer = io.BytesIO()
        with h5py.File(buffer, "w") as f:
            fill(f)
        data = buffer.getvalue()
        write("granule", name, data)
        return data

    def gedi(f, numbers=np.array([1, 2], "u8"), lat=(1.0, 1.001)):
        for beam in ("BEAM0000", "BEAM0101"):
            f[beam + "/shot_number"] = numbers
            f[beam + "/lat_lowestmode"] = np.array(lat)
            f[beam + "/lon_lowestmode"] = np.array([2.0, 2.0])
            f[beam + "/delta_time"] = np.array([1.0, 1.1])
            f[beam + "/degrade_flag"] = np.array([0, 1], "u1")

    def glah14(f, record=np.array([7, 7], "i4"), count=np.array([39, 40], "i2")):
        f["Data_40HZ/Geolocation/d_lat"] = np.array([1.0, 1.001])
        f["Data_40HZ/Geolocation/d_lon"] = np.array([2.0, 2.0])
        f["Data_40HZ/Time/d_UTCTime_40"] = np.array([1.0, 1.025])
        f["Data_40HZ/Time/i_rec_ndx"] = record
        f["Data_40HZ/Time/i_shot_count"] = count

    whole = h5("gedi.h5", gedi)
    write("granule", "broken-gedi-truncated.h5", whole[: len(whole) // 2])
    h5("broken-gedi-huge-number.h5", lambda f: gedi(f, np.array([2**63 + 1, 2], "u8")))
    h5("broken-gedi-float-number.h5", lambda f: gedi(f, np.array([1.5, 2.0])))
    h5("broken-gedi-fill.h5", lambda f: gedi(f, lat=(-999999.0, 1.0)))
    whole = h5("glah14.h5", glah14)
    write("granule", "broken-glah14-truncated.h5", whole[: len(whole) * 3 // 4])
    h5("broken-glah14-overflow.h5", lambda f: glah14(f, np.array([2**61, 1], "i8")))
    h5("broken-glah14-count.h5", lambda f: glah14(f, count=np.array([0, 41], "i2")))

    def declared(f):
        f.create_dataset("BEAM0000/shot_number", data=np.array([1], "u8"))
        f.create_dataset("BEAM0000/lat_lowestmode", shape=(10**11,), dtype="f8", chunks=(1024,))
    h5("broken-declared-1e11.h5", declared)


def retrieval_corpus():
    """Small granules of the kinds retrieve reads: GEDI L1B and L2A, GLAH01 and GLAH14 (shots
    that match), ATL08, ATL03, and an L1B cut short and one declaring 10^11 samples."""
    import io
    import h5py
    import numpy as np

    def h5(name, fill):
        buffer = io.BytesIO()
        with h5py.File(buffer, "w") as f:
            fill(f)
        data = buffer.getvalue()
        write("retrieval", name, data)
        return data

    wave = 200.0 + 500.0 * np.exp(-0.5 * ((np.arange(24) - 16) / 2.0) ** 2)

    def l1b(f, samples=None):
        for beam in ("BEAM0000", "BEAM0101"):
            g = f.create_group(beam)
            g["shot_number"] = np.array([1, 2], "u8")
            if samples is None:
                g["rxwaveform"] = np.concatenate([wave, wave]).astype("f4")
            else:
                g.create_dataset("rxwaveform", shape=(samples,), dtype="f4", chunks=(1024,))
            g["rx_sample_start_index"] = np.array([1, 25], "u8")
            g["rx_sample_count"] = np.array([24, 24], "u2")
            g["noise_mean_corrected"] = np.array([200.0, 200.0])
            g["noise_stddev_corrected"] = np.array([2.0, 2.0])
            g["geolocation/elevation_bin0"] = np.array([103.6, 103.6])
            g["geolocation/elevation_lastbin"] = np.array([100.15, 100.15])
            g["geolocation/latitude_bin0"] = np.array([1.0, 1.001])
            g["geolocation/longitude_bin0"] = np.array([2.0, 2.0])
            g["geolocation/degrade"] = np.array([0, 0], "i1")
        f["glaswave_truth/counts_per_watt"] = np.array([1e9])

    whole = h5("gedi_l1b.h5", l1b)
    write("retrieval", "broken-gedi-l1b-truncated.h5", whole[: len(whole) // 2])
    h5("broken-gedi-l1b-declared-1e11.h5", lambda f: l1b(f, 10**11))

    def l2a(f):
        g = f.create_group("BEAM0101")
        g["shot_number"] = np.array([1, 2], "u8")
        g["elev_lowestmode"] = np.array([100.5, 100.5], "f4")
        g["elev_highestreturn"] = np.array([103.0, 103.0], "f4")
        g["quality_flag"] = np.array([1, 0], "u1")
        g["selected_algorithm"] = np.array([1, 2], "u1")
    h5("gedi_l2a.h5", l2a)

    def glah01(f):
        d = f.create_group("Data_40HZ")
        d["Time/i_rec_ndx"] = np.array([1000, 1000, 1001], "i4")
        d["Time/i_shot_count"] = np.array([1, 2, 40], "i2")
        d["Waveform/RecWaveform/r_rng_wf"] = np.tile(wave, (3, 1)).astype("f4")
        d["Waveform/Characteristics/d_4nsBgMean"] = np.full(3, 200.0)
        d["Waveform/Characteristics/d_4nsBgSDEV"] = np.full(3, 2.0)
        d["Waveform/RecWaveform/i_rec_wf_location_index"] = np.array([1, 1, 127], "i1")
        d["glaswave_truth/counts_per_watt"] = np.array([1e9])
        a = f.create_group("ANCILLARY_DATA")
        a.attrs["rec_wf_sample_location_table"] = (np.arange(24.0) - 23.0).reshape(1, 24)
    h5("glah01.h5", glah01)

    def glah14(f):
        d = f.create_group("Data_40HZ")
        d["Time/i_rec_ndx"] = np.array([1000, 1000], "i4")
        d["Time/i_shot_count"] = np.array([1, 2], "i2")
        d["Geolocation/d_lat"] = np.array([1.0, 1.001])
        d["Geolocation/d_lon"] = np.array([358.0, 358.0])
        d["Elevation_Surfaces/d_elev"] = np.array([101.0, 101.0])
        d["Elevation_Offsets/d_ldRngOff"] = np.array([-1.0, 1.7976931348623157e308])
    h5("glah14.h5", glah14)

    def atl08(f):
        land = f.create_group("gt1l/land_segments")
        land["segment_id_beg"] = np.array([101, 106], "i4")
        land["latitude"] = np.array([10.0, 10.001], "f4")
        land["longitude"] = np.array([20.0, 20.0], "f4")
        land["canopy/h_canopy"] = np.array([17.5, 3.4028235e38], "f4")
        land["terrain/h_te_best_fit"] = np.array([250.25, 250.5], "f4")
        land["canopy/n_ca_photons"] = np.array([30, 0], "i4")
        land["canopy/n_toc_photons"] = np.array([10, 0], "i4")
        land["terrain/n_te_photons"] = np.array([60, 5], "i4")
    h5("atl08.h5", atl08)

    def atl03(f):
        # gt1l's photons in 20 m segments 101-106 (the fuzzer's companion ATL08 holds 101-105).
        g = f.create_group("gt1l")
        g["heights/h_ph"] = np.array([250.0, 262.5, 251.0, 263.0, 249.5, 258.0, 252.0], "f4")
        g["heights/dist_ph_along"] = np.array([1.0, 5.0, 2.0, 18.0, 0.5, 10.0, 19.5], "f4")
        g["heights/delta_time"] = 1000.0 + 0.0014 * np.arange(7)
        g["geolocation/segment_id"] = np.arange(101, 107, dtype="i4")
        g["geolocation/segment_dist_x"] = 20.0 * np.arange(101, 107)
        g["geolocation/ph_index_beg"] = np.array([1, 3, 5, 0, 7, 0], "i8")
        g["geolocation/segment_ph_cnt"] = np.array([2, 2, 2, 0, 1, 0], "i4")
        g["geolocation/delta_time"] = 1000.0 + 0.002857 * np.arange(6)
        g["bckgrd_atlas/bckgrd_rate"] = np.array([1e6, 2e6], "f4")
        g["bckgrd_atlas/delta_time"] = np.array([1000.0, 1000.005])
        g["glaswave_truth/photons_per_joule"] = np.array([1.8e17])
    h5("atl03.h5", atl03)


def gdal_pack(kind, value):
    import struct
    return struct.pack({gdal.GDT_Float32: "<f", gdal.GDT_Int16: "<h"}[kind], value)


def las_bytes(minor, fmt, points, wkt=None, geo_keys=None, extra=0):
    """A LAS file from the ASPRS LAS 1.4 tables: header of the version's size, records, points."""
    import struct
    lengths = [20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67]
    header = 375 if minor >= 4 else 235 if minor == 3 else 227
    vlrs = []

    def vlr(record_id, data):
        vlrs.append(struct.pack("<H16sHH32s", 0, b"LASF_Projection", record_id, len(data), b"")
                    + data)
    if wkt:
        vlr(2112, wkt.encode() + b"\0")
    if geo_keys:
        vlr(34735, struct.pack("<4H", 1, 1, 0, len(geo_keys))
            + b"".join(struct.pack("<4H", k, 0, 1, v) for k, v in geo_keys))
    length = lengths[fmt] + extra
    offset = header + sum(len(v) for v in vlrs)
    h = bytearray(header)
    h[0:4] = b"LASF"
    h[24], h[25] = 1, minor
    struct.pack_into("<HIIBHI", h, 94, header, offset, len(vlrs), fmt, length,
                     len(points) if fmt <= 5 else 0)
    struct.pack_into("<6d", h, 131, 0.01, 0.01, 0.01, 500000.0, 4000000.0, 0.0)
    if minor >= 4:
        struct.pack_into("<H", h, 6, 16 if wkt else 0)
        struct.pack_into("<Q", h, 247, len(points))
    body = b""
    for i, (x, y, z, ret, n, cls) in enumerate(points):
        r = bytearray(length)
        struct.pack_into("<iiiH", r, 0, round((x - 500000) / 0.01), round((y - 4000000) / 0.01),
                         round(z / 0.01), 50)
        if fmt >= 6:
            r[14], r[16] = ret | n << 4, cls
            struct.pack_into("<d", r, 22, 1.5 * i)
        else:
            r[14], r[15] = ret | n << 3, cls
            if fmt not in (0, 2):
                struct.pack_into("<d", r, 20, 1.5 * i)
        body += bytes(r)
    return bytes(h) + b"".join(vlrs) + body


def las_corpus():
    pts = [(500001.0, 4000002.0, 12.5, 1, 2, 5), (500001.0, 4000002.0, 0.3, 2, 2, 2),
           (500003.5, 3999999.0, 0.1, 1, 1, 2)]
    utm = ('PROJCS["WGS 84 / UTM zone 33N",GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",'
           '6378137,298.257223563]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]],'
           'PROJECTION["Transverse_Mercator"],PARAMETER["latitude_of_origin",0],'
           'PARAMETER["central_meridian",15],PARAMETER["scale_factor",0.9996],'
           'PARAMETER["false_easting",500000],PARAMETER["false_northing",0],UNIT["metre",1]]')
    write("las", "v12-format0.las", las_bytes(2, 0, pts))
    write("las", "v12-format3-keys.las", las_bytes(2, 3, pts, geo_keys=[(1024, 1), (3072, 32633)]))
    write("las", "v13-format5.las", las_bytes(3, 5, pts, extra=4))
    write("las", "v14-format6-wkt.las", las_bytes(4, 6, pts, wkt=utm))
    write("las", "v14-format10.las", las_bytes(4, 10, pts, wkt=utm))
    good = las_bytes(4, 7, pts, wkt=utm)
    write("las", "broken-truncated.las", good[: len(good) - 10])
    write("las", "broken-laz.las", good[:104] + bytes([good[104] | 0x80]) + good[105:])
    write("las", "broken-count.las", good[:247] + (1000).to_bytes(8, "little") + good[255:])


def journal_corpus():
    """The journal target builds its journals from the input (frames of records, then a frame
    repeated, dropped, a cut or a flipped byte): random bytes reach each; "GWJRNL" + bytes is
    what follows the header as it is."""
    rng = random.Random(28)
    for i in range(6):
        write("journal", "described-%d" % i, bytes(rng.randrange(256) for _ in range(64)))
    write("journal", "raw-marker-only", b"GWJRNL" + (0x454d415246574721).to_bytes(8, "little"))


def mesh_corpus():
    """The mesh target's first byte picks the extension (0 .ply, 1 .obj, 2 .gltf, 3 .glb, 4 .stl,
    5 .off); the rest is the file."""
    import base64
    import struct
    ply = ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
           "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
           "0 0 0\n1 0 0\n0 1 0\n")
    write("mesh", "triangle-ply", b"\x00" + (ply + "3 0 1 2\n").encode())
    binary = ply.replace("ascii", "binary_little_endian").split("0 0 0")[0].encode() + \
        struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<B3i", 3, 0, 1, 2)
    write("mesh", "triangle-binary-ply", b"\x00" + binary)
    write("mesh", "broken-index-ply", b"\x00" + (ply + "3 0 1 100000000\n").encode())
    write("mesh", "broken-count-ply", b"\x00" + ply.replace("face 1", "face 1000000000").encode())
    write("mesh", "plate-obj", b"\x01" + b"mtllib plate.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
          b"usemtl leaf\nf 1 2 3\nf 1 2 -7\n")
    vertices = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    gltf = {"asset": {"version": "2.0"},
            "buffers": [{"uri": "data:application/octet-stream;base64," +
                         base64.b64encode(vertices).decode(), "byteLength": 36}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 0]}],
            "materials": [{"name": "leaf"}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
            "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0}
    write("mesh", "plate-gltf", b"\x02" + json.dumps(gltf).encode())
    text = json.dumps(dict(gltf, buffers=[{"byteLength": 36}])).encode()
    text += b" " * (-len(text) % 4)
    glb = (struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(text) + 8 + 36) +
           struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", 36, b"BIN\0") +
           vertices)
    write("mesh", "plate-glb", b"\x03" + glb)
    write("mesh", "plate-stl", b"\x04" + b"solid plate\nfacet normal 0 0 1\nouter loop\n"
          b"vertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid plate\n")
    write("mesh", "plate-off", b"\x05" + b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")


def voxel_corpus():
    """The voxel target's first byte picks the format (even .nc, odd .tif); the rest is the file.
    Grids of 3 layers over 4 x 4 columns in UTM 32N, as netCDF4-python and GDAL write them."""
    import os
    import shutil
    import tempfile

    import netCDF4
    import numpy
    utm = osr.SpatialReference()
    utm.ImportFromEPSG(32632)
    folder = tempfile.mkdtemp()
    path = os.path.join(folder, "grid.nc")
    for name, packed in (("grid-nc", False), ("packed-nc", True)):
        with netCDF4.Dataset(path, "w") as nc:
            for d, n in (("z", 3), ("y", 4), ("x", 4), ("nv", 2)):
                nc.createDimension(d, n)
            nc.createVariable("x", "f8", ("x",))[:] = 430000.0 + numpy.arange(4)
            nc.createVariable("y", "f8", ("y",))[:] = 5090000.0 + numpy.arange(4)
            z = nc.createVariable("z", "f8", ("z",))
            z[:] = [1.0, 3.0, 5.0]
            z.bounds = "z_bounds"
            nc.createVariable("z_bounds", "f8", ("z", "nv"))[:] = [[0, 2], [2, 4], [4, 6]]
            crs = nc.createVariable("crs", "i4")
            crs.crs_wkt = utm.ExportToWkt()
            pad = nc.createVariable("pad", "i2" if packed else "f4", ("z", "y", "x"),
                                    fill_value=-1 if packed else None)
            if packed:
                pad.scale_factor = 0.01
            pad.grid_mapping = "crs"
            pad[:] = numpy.full((3, 4, 4), 0.5)
        with open(path, "rb") as f:
            write("voxel", name, b"\x00" + f.read())
    path = os.path.join(folder, "grid.tif")
    raster = gdal.GetDriverByName("GTiff").Create(path, 4, 4, 3, gdal.GDT_Float32)
    raster.SetGeoTransform([430000.0, 1.0, 0.0, 5090004.0, 0.0, -1.0])
    raster.SetProjection(utm.ExportToWkt())
    for b in range(3):
        band = raster.GetRasterBand(b + 1)
        band.WriteArray(numpy.full((4, 4), 0.5, dtype=numpy.float32))
        band.SetMetadataItem("z_bottom_m", str(2 * b))
        band.SetMetadataItem("z_top_m", str(2 * b + 2))
    raster = None
    with open(path, "rb") as f:
        tif = f.read()
    write("voxel", "grid-tif", b"\x01" + tif)
    write("voxel", "broken-truncated-tif", b"\x01" + tif[: len(tif) // 2])
    shutil.rmtree(folder)


if __name__ == "__main__":
    config_corpus()
    csv_corpus()
    ephemeris_corpus()
    stands_corpus()
    dem_corpus()
    las_corpus()
    granule_corpus()
    retrieval_corpus()
    journal_corpus()
    mesh_corpus()
    voxel_corpus()
