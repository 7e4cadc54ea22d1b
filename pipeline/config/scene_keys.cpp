// The keys of what a shot sees and how it is traced: `simulation`, `terrain`, `canopy`, `track`.
#include "canopy/canopy_settings.hpp"
#include "canopy/vegetation_traits.hpp"
#include "core/part_kind.hpp"
#include "footprints/track_settings.hpp"
#include "pipeline/config/config.hpp"
#include "pipeline/config/key_fields.hpp"
#include "terrain/terrain_settings.hpp"

namespace glaswave::section_keys {

using nlohmann::json;
using namespace declare;

namespace {

constexpr double wgs84_equatorial_radius_m = 6378137.0;

Key background_key() {
  Key background = make("background", KeyType::choice_or_object, "",
                        "photon counting's background light: `sun` (the sun at each shot's time "
                        "and place over a Lambertian scene of the shot's reflectance), `none`, or "
                        "`{\"rate_MHz\": R}` detected photons a microsecond");
  background.default_value = "sun";
  background.choices = {"sun", "none"};
  background.children = {number("rate_MHz", std::nullopt, at_least(0), "MHz",
                                "background photons detected a "
                                "microsecond")
                             .with_required()};
  return background;
}

}  // namespace

Key simulation_keys() {
  const Fields<SimulationSettings> s;
  using S = SimulationSettings;
  return object(
      "simulation", "the Monte Carlo transport",
      {s.integer("rays_per_shot", &S::rays_per_shot, 1, run_limits::rays_per_shot, "",
                 "Monte Carlo rays a shot (error falls as n^−1/2)"),
       s.integer("max_order", &S::max_order, 1, run_limits::max_order, "",
                 "highest scattering order"),
       s.choice_of("sampling", &S::quasi_random, {{"random", false}, {"sobol", true}},
                   "how rays draw their beam direction and first free path: `random` "
                   "(plain Monte Carlo) or `sobol` (the shot's scrambled Sobol' points: "
                   "unbiased; on the seed's base case the mean waveform's error at 10^4 "
                   "rays is that of 1.9× the rays at the same cost; the noise the processing "
                   "weighs its fits with, computed for independent rays, is then overstated)"),
       background_key()});
}

Key terrain_keys() {
  const TerrainSettings t;
  const Fields<TerrainSettings> f;
  const Fields<PlaneSettings> p;
  const Fields<RoughnessSettings> g;
  Key dem =
      path("dem",
           "a raster GDAL reads, with a CRS (geographic or projected; nodata honoured); "
           "exactly one of `dem`, `plane` and `point_cloud`. A shot whose beam (3 σ) falls over "
           "nodata or "
           "off the raster is flagged, its waveform fill. An unusable file (missing, corrupt, "
           "truncated, no CRS) is an error, exit status 3");
  Key dem_band = integer("dem_band", std::nullopt, 1, int_max, "",
                         "`dem` only: the band of heights (from 1); required when the raster has "
                         "more than one");
  Key datum = choice(
      "vertical_datum", t.vertical_datum, {"ellipsoid", "egm96"},
      "`dem` and `point_cloud` only: what the DEM's (the cloud's) heights are measured from when "
      "its CRS has no vertical part: "
      "`ellipsoid` (its own), `egm96` (the EGM96 geoid, through PROJ's `egm96_15.gtx`), or a "
      "vertical CRS PROJ knows (`EPSG:3855` when its grid is installed). A DEM with a vertical "
      "CRS of its own uses it when this key is not set; set to another datum, it is refused. The "
      "choice made is in the run summary and in the products' `config`");
  datum.open_choices = true;
  datum.what_else = "a vertical CRS as AUTHORITY:CODE";
  datum.pattern = std::string(":");  // not = ":": GCC 12 warns falsely (-Wrestrict)
  Key terrain =
      object(
          "terrain", "the ground: exactly one of `dem`, `plane` and `point_cloud`",
          {std::move(dem),
           f.object("plane", &TerrainSettings::plane,
                    "a synthetic plane, anchored at the origin's latitude and longitude, for slope "
                    "studies; exactly one of `dem`, `plane` and `point_cloud`",
                    {p.number("origin_lat_deg", &PlaneSettings::origin_lat_deg, closed(-90, 90),
                              "deg", "latitude of the origin"),
                     p.number("origin_lon_deg", &PlaneSettings::origin_lon_deg, closed(-180, 360),
                              "deg", "longitude of the origin"),
                     p.number("elevation_m", &PlaneSettings::elevation_m, closed(-1e5, 1e5), "m",
                              "height of the origin above WGS84"),
                     p.number("slope_deg", &PlaneSettings::slope_deg, closed(0, 89), "deg",
                              "slope of the plane"),
                     p.number("aspect_deg", &PlaneSettings::aspect_deg, any_finite(), "deg",
                              "the azimuth the slope faces (clockwise from north)")}),
           f.boolean("point_cloud", &TerrainSettings::point_cloud,
                     "`true`: the ground of `canopy.point_cloud`'s cloud (its class-2 points "
                     "gridded on its voxels' columns, as `glaswave voxelize` writes "
                     "`ground_elevation`), without a DEM file; exactly one of `dem`, `plane` and "
                     "`point_cloud`, and only with a `canopy.point_cloud`; `false` is refused "
                     "(give `dem` or `plane` instead)",
                     "absent")
               .with_only(true),
           std::move(dem_band), std::move(datum),
           f.object(
               "roughness", &TerrainSettings::roughness,
               "random relief added under the beam (a Gaussian random field with covariance "
               "exp(−r²/L²), fixed by position and `seed`, meshed every L/3, or L/2 or L where the "
               "field of view needs more than 1024 nodes a side, else refused)",
               {g.number("rms_m", &RoughnessSettings::rms_m, at_least(0), "m",
                         "RMS height of the relief"),
                g.number("correlation_m", &RoughnessSettings::correlation_m, above(0), "m",
                         "correlation length L")}),
           spectral("soil_reflectance", 0.15, closed(0, 1), "", "Lambertian soil, per band")})
          .with_required();
  return terrain;
}

Key canopy_keys() {
  const CanopySettings c;
  const Fields<CanopySettings> f;
  using S = CanopySettings;
  Key lad = make("lad", KeyType::choice_or_object, "",
                 "leaf angle distribution: a name, or `{\"ellipsoidal_mean_deg\": X}` for "
                 "Campbell's ellipsoidal distribution");
  lad.default_value = "spherical";
  lad.choices = {"spherical",   "planophile",   "erectophile",
                 "plagiophile", "extremophile", "uniform"};
  lad.children = {number("ellipsoidal_mean_deg", std::nullopt, open(0, 90), "deg",
                         "mean leaf inclination of the ellipsoidal distribution")
                      .with_required()};
  // canopy.voxels and canopy.point_cloud: measured vegetation instead of crowns (PRODUCT.md
  // section 8); their leaves' keys are the canopy's, with the defaults of a grid of leaves.
  const auto leaves = [&] {
    return std::vector<Key>{Key(lad),
                            f.number("leaf_size_m", &S::leaf_size_m, at_least(0), "m",
                                     "the hotspot's correlation length; 0 is the point-leaf limit"),
                            spectral("leaf_reflectance", 0.4, closed(0, 1), "", "per band"),
                            spectral("leaf_transmittance", 0.4, closed(0, 1), "",
                                     "per band; `leaf_reflectance` + `leaf_transmittance` ≤ 1"),
                            f.number("bark_fraction", &S::bark_fraction, closed(0, 1), "",
                                     "the bark's part of the plant area (opaque, Lambertian)")
                                .with_default(0.0),
                            spectral("bark_reflectance", 0.3, closed(0, 1), "", "per band")};
  };
  std::vector<Key> voxel_keys = leaves();
  voxel_keys.insert(voxel_keys.begin(),
                    f.path("file", &S::voxels_file,
                           "plant area density (m²/m³) on a regular grid: a CF NetCDF variable "
                           "`pad(z, y, x)` with a CRS, z the height above the ground; or a "
                           "multi-band GeoTIFF, band i the slice between its metadata `z_bottom_m` "
                           "and `z_top_m`")
                        .with_required());
  std::vector<Key> cloud_keys = leaves();
  cloud_keys.insert(
      cloud_keys.begin(),
      {f.path("file", &S::point_cloud_file,
              "an airborne lidar point cloud, LAS 1.0–1.4 uncompressed (LAZ: decompress it with "
              "`laszip` or `pdal translate`), voxelised at start by gap-fraction inversion as "
              "`glaswave voxelize` does")
           .with_required(),
       f.string("crs", &S::point_cloud_crs,
                "the cloud's CRS when the file has no WKT or GeoTIFF-keys record (`EPSG:32633`, "
                "WKT, PROJ)"),
       f.number("voxel_size_m", &S::voxel_size_m, closed(0.05, 100), "m",
                "the voxels' width and depth")});
  Key canopy = object(
      "canopy",
      "the vegetation (names of the seed's Table 1): bare ground when null or absent; `{}` is "
      "Table 1. Leaves are bi-Lambertian, bark and soil Lambertian. Trees stand on the local "
      "ground; the same tree is in the same place for every shot that sees it",
      {f.number("pai", &S::pai, at_least(0), "m²/m²",
                "one-sided plant area of leaves and bark per unit ground area of the scene (with "
                "`crowns_file`: of the crowns' bounding box)"),
       std::move(lad),
       f.number("cover", &S::cover, closed(0, 1), "",
                "crown cover, crowns placed at random (below 1 unless `crown_shape` is `layer`)"),
       number("green_fraction", c.green_fraction, closed(0, 1), "",
              "the leaves' part of the plant area; 1 − `bark_fraction` when only that is given"),
       number("bark_fraction", c.bark_fraction, closed(0, 1), "",
              "the bark's part of the plant area; 1 − `green_fraction` when only that is given; "
              "the two add up to 1"),
       f.choice_of(
           "crown_shape", &S::crown_shape,
           {{"ellipsoid", CrownShape::ellipsoid},
            {"cone", CrownShape::cone},
            {"layer", CrownShape::layer}},
           "`ellipsoid`, `cone`, or `layer`: a homogeneous slab over the whole scene, "
           "`crown_base_m[0]` to `crown_base_m[0] + 2 crown_half_height_m` above the ground "
           "(`pai` is its total)"),
       // No tree is wider or taller than 100 m; a crown of 1e6 m made the stand lookup run for
       // minutes.
       f.number("crown_radius_m", &S::crown_radius_m, open_closed(0, 100), "m", "crown radius"),
       f.number("crown_half_height_m", &S::crown_half_height_m, open_closed(0, 100), "m",
                "crown half height"),
       number_pair(
           "crown_base_m", c.crown_base_m, at_least(0), "m",
           "[min, max]: crown bases uniform in this range above the terrain under the stem"),
       f.number("leaf_size_m", &S::leaf_size_m, at_least(0), "m",
                "the hotspot's correlation length; 0 is the point-leaf limit"),
       f.number("dbh_m", &S::dbh_m, at_least(0), "m",
                "trunk diameter; trunks from the ground to the crown"),
       spectral("leaf_reflectance", 0.4, closed(0, 1), "", "per band"),
       spectral("leaf_transmittance", 0.4, closed(0, 1), "",
                "per band; `leaf_reflectance` + `leaf_transmittance` ≤ 1"),
       spectral("bark_reflectance", 0.3, closed(0, 1), "", "per band"),
       f.path("crowns_file", &S::crowns_file,
              "a CSV of explicit crowns instead of random ones: header "
              "`lon,lat,base_m,radius_m,half_height_m` (degrees) or "
              "`x,y,base_m,radius_m,half_height_m` (metres east and north of `terrain.plane`'s "
              "origin); `pai` is then per unit area of the crowns' bounding box"),
       f.path("stands", &S::stands,
              "a vector file GDAL/OGR reads (GeoJSON, GeoPackage, Shapefile, FlatGeobuf...) of "
              "Polygons or MultiPolygons, every layer's features, whose attribute fields (GeoJSON "
              "`properties`) override canopy keys inside them (`{\"pai\": 1.5, \"lad\": "
              "\"erectophile\"}`; a text field holding a JSON object or array is read as that "
              "JSON); in any CRS, brought to WGS84 with PROJ: a layer without one is taken as "
              "longitude and latitude, and is an error if its coordinates are not; checked like "
              "the configuration, a bad file is exit status 3 naming the feature and key; not with "
              "a `layer`"),
       object("voxels",
              "a voxel grid of plant area density instead of crowns (no other canopy key "
              "beside it): each voxel a turbid cell of these leaves, each column standing on "
              "the terrain under its centre",
              std::move(voxel_keys)),
       object("point_cloud",
              "an airborne lidar point cloud instead of crowns (no other canopy key beside it): "
              "ground points (class 2) and the other returns voxelised by gap-fraction "
              "inversion, each voxel a turbid cell of these leaves",
              std::move(cloud_keys)),
       object(
           "facets",
           "facet trees instead of crowns (no other canopy key beside it): triangle meshes or "
           "disc leaves, one shared model each, placed by `trees_file`, each tree standing on "
           "the terrain under its stem (or floating `z_m` above it)",
           {f.path(
                 "trees_file", &S::facet_trees_file,
                 "the trees: a `.csv` with header `lon,lat,model,rotation_deg,scale` (degrees) or "
                 "`x,y,model,rotation_deg,scale` (metres east and north of `terrain.plane`'s "
                 "origin), either with a last column `z_m` (the model's origin above the ground, "
                 "0 to 1000 m; 0 when absent), or any vector file OGR reads of points (in any "
                 "CRS) with the attributes `model`, `rotation_deg` and `scale` (and optionally "
                 "`z_m`); `rotation_deg` turns the model's +y axis to that azimuth (clockwise "
                 "from north)")
                .with_required(),
            map("models",
                "each model's name and its file: a mesh (any format Assimp reads: OBJ, PLY, "
                "glTF, ...; metres, z up, the stem's foot at the origin), or leaves as discs in "
                "RAMI's text, a `*.def` file of one disc a line `radius x y z nx ny nz` (metres, "
                "the model's frame), all of `disc_material`",
                path("NAME", "the mesh or disc leaf file"))
                .with_required(),
            f.bind(declare::string("disc_material", std::nullopt,
                                   "the material (an entry of `materials`, two-sided when it "
                                   "has a `transmittance`) of every disc of the disc leaf "
                                   "models")
                       .with_default_text("`leaf`"),
                   &S::facet_disc_material,
                   [](JsonReader& r, const std::string& key) {
                     return r.optional_string(key).value_or("leaf");
                   }),
            map("materials",
                "the optics of each material name the meshes use (a mesh material without an "
                "entry is an error)",
                object("NAME",
                       "a leaf when `transmittance` is given (two-sided bi-Lambertian), else "
                       "opaque and Lambertian (wood)",
                       {spectral("reflectance", 0.0, closed(0, 1), "", "per band").with_required(),
                        spectral("transmittance", 0.0, closed(0, 1), "",
                                 "per band; given: a two-sided leaf, `reflectance` + "
                                 "`transmittance` ≤ 1")
                            .with_default_text("none: opaque")}))
                .with_required()})});
  // A kind whose keys the configuration does not declare is chosen by its empty object.
  for (const auto& kind : Registry<PartKind<VegetationTraits>>::instance().entries())
    if (kind.make.traits.keys == VegetationTraits::Keys::none)
      canopy.children.push_back(
          object(kind.name, kind.make.description + " (no other canopy key beside it)", {}));
  canopy.default_text = "null";
  return canopy;
}

Key track_keys() {
  const Fields<TrackSettings> t;
  const Fields<OrbitElements> o;
  using S = TrackSettings;
  using O = OrbitElements;
  return object(
      "track", "the shots: where they are and how the beam points",
      {t.choice_of("type", &S::type,
                   {{"pass", TrackType::pass},
                    {"points", TrackType::points},
                    {"orbit", TrackType::orbit},
                    {"ephemeris", TrackType::ephemeris},
                    {"granule", TrackType::granule}},
                   "how shots are placed: `pass`, `points`, `orbit`, `ephemeris` or `granule`"),
       t.number("start_lat_deg", &S::start_lat_deg, closed(-90, 90), "deg",
                "`pass`: the spacecraft flies the geodesic from here along the heading"),
       t.number("start_lon_deg", &S::start_lon_deg, closed(-180, 360), "deg",
                "`pass`: see `start_lat_deg`"),
       t.number("heading_deg", &S::heading_deg, any_finite(), "deg",
                "`pass`: the heading, clockwise from north"),
       t.integer("shots", &S::shots, 1, run_limits::track_shots, "",
                 "shots of a pass. `orbit`: shots at `rate_hz` from `start_time`, numbered by "
                 "their place in that sequence; only those whose footprint falls on the terrain "
                 "are simulated and written, the others skipped (`check` says how many). "
                 "`points`: the number of points"),
       t.number("rate_hz", &S::rate_hz, above(0), "Hz", "shot rate (times)")
           .with_default_text("`sensor.pulse_rate_hz`"),
       t.number("spacing_m", &S::spacing_m, above(0), "m",
                "spacing of shots along track; from the orbital ground speed and `rate_hz` when "
                "not given")
           .with_default_text("from speed"),
       t.number("altitude_m", &S::altitude_m, open_closed(0, run_limits::altitude_m), "m",
                "spacecraft height above WGS84 (`pass`, `points`, `granule`)"),
       time("start_time", "2000-01-01T12:00:00Z", "ISO 8601 UTC time of shot 0"),
       t.number("off_nadir_deg", &S::off_nadir_deg, half_open(0, 45), "deg",
                "beam tilted from geodetic nadir, for every type; a track none of whose shots "
                "meets the terrain is an error (exit status 3)"),
       t.number("pointing_azimuth_deg", &S::pointing_azimuth_deg, any_finite(), "deg",
                "the azimuth the beam is tilted toward (clockwise from north)"),
       object_array(
           "points", json(), "`points`: targets on the ground, one shot each",
           {number("lat_deg", std::nullopt, closed(-90, 90), "deg", "latitude").with_required(),
            number("lon_deg", std::nullopt, closed(-180, 360), "deg", "longitude").with_required()})
           .with_items(1, run_limits::track_shots),
       o.number("semi_major_axis_m", &O::semi_major_axis_m,
                open_closed(wgs84_equatorial_radius_m,
                            wgs84_equatorial_radius_m + run_limits::altitude_m),
                "m",
                "`orbit`: mean elements at `epoch` in the true-equator mean-equinox frame (as "
                "two-line elements), propagated with the J2 secular drift of node, perigee and "
                "mean anomaly, turned Earth-fixed with GMST (UT1 taken as UTC)"),
       o.number("eccentricity", &O::eccentricity, half_open(0, 1), "",
                "`orbit`: the perigee must be above the Earth"),
       o.number("inclination_deg", &O::inclination_deg, closed(0, 180), "deg", "`orbit`"),
       o.number("raan_deg", &O::raan_deg, any_finite(), "deg",
                "`orbit`: right ascension of the ascending node"),
       o.number("arg_perigee_deg", &O::arg_perigee_deg, any_finite(), "deg",
                "`orbit`: argument of perigee"),
       o.number("mean_anomaly_deg", &O::mean_anomaly_deg, any_finite(), "deg", "`orbit`"),
       time("epoch", std::nullopt, "`orbit`: ISO 8601 UTC time of the elements")
           .with_default_text("`start_time`"),
       t.path("ephemeris", &S::ephemeris,
              "`ephemeris`: a CSV file, one shot a row, with a header row "
              "`time,x_m,y_m,z_m[,pointing_x,pointing_y,pointing_z]` (any order): time as ISO "
              "8601 UTC or seconds since 2000-01-01T12:00:00Z, the spacecraft's WGS84 Earth-fixed "
              "position (m), and optionally the beam direction (Earth-fixed, any length); without "
              "it the beam points by `off_nadir_deg` and `pointing_azimuth_deg`. Lines starting "
              "with `#` are skipped; errors name `file:line`"),
       t.path("file", &S::granule,
              "`granule`: a GEDI L2A granule (groups `BEAM0000` to `BEAM1011`, GEDI's eight "
              "beams, with `shot_number`, `lat_lowestmode`, `lon_lowestmode`, `delta_time`) or a "
              "GLAS GLAH14 granule (`Data_40HZ` with `Geolocation/d_lat`, `d_lon`, "
              "`Time/d_UTCTime_40`, `i_rec_ndx`, `i_shot_count`: all required), "
              "HDF5: one shot per footprint, aimed at its latitude and longitude from `altitude_m` "
              "as a point is, at its time, its `shot_number` the granule's (GLAH14: `i_rec_ndx` * "
              "40 + the shot in its record); footprints whose position is a fill value are "
              "skipped"),
       t.string_array("beams", &S::beams,
                      "`granule`: the beams to take, by group name (`[\"BEAM0101\"]`; GLAH14's one "
                      "is `Data_40HZ`); a beam not in the file is exit status 3")
           .with_default_text("all")});
}

}  // namespace glaswave::section_keys
