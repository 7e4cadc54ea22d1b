// shots.nc's layout: its global attributes (CF, ACDD), dimensions, the variables every shot
// shares (bands, bin times, the transmitted pulse, the CRS), and the per-shot variables, defined
// from the product field table (product_fields.hpp) with their chunking, compression and fill.
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "core/glas_time.hpp"
#include "pipeline/products/netcdf_writer_impl.hpp"

namespace glaswave {
namespace {

// Level 2 already takes most of what deflate can from waveforms (long runs of zero power
// before and after the return); higher levels cost time for little more.
constexpr int kDeflateLevel = 2;
// Every per-shot variable is chunked whole shots at a time, as many as fit in this many bytes
// (a power of two of them, at most kMostShotsPerChunk): a whole variable reads in a few chunks,
// one shot in one chunk of at most this size (16 shots of two bands' waveforms).
constexpr std::size_t kChunkTarget_B = 128 * 1024;
constexpr std::size_t kMostShotsPerChunk = 1024;
// Photon events are chunked along `photon` alone: 4096 of them (32 KiB of a float64 variable).
constexpr std::size_t kPhotonsPerChunk = 4096;
// The coordinates of a trajectory; they carry no `coordinates` attribute themselves.
constexpr const char* kShotCoordinates = "time lat lon";
// The grid mapping variable every geolocated variable names.
constexpr const char* kCrsVariable = "crs";
// EPSG:4979, WGS 84 with ellipsoidal heights: latitude, longitude and every elevation of the
// product are geodetic coordinates on the WGS 84 ellipsoid.
constexpr const char* kCrsWkt =
    R"wkt(GEOGCRS["WGS 84",DATUM["World Geodetic System 1984",ELLIPSOID["WGS 84",6378137,)wkt"
    R"wkt(298.257223563,LENGTHUNIT["metre",1]]],PRIMEM["Greenwich",0,ANGLEUNIT["degree",)wkt"
    R"wkt(0.0174532925199433]],CS[ellipsoidal,3],AXIS["geodetic latitude (Lat)",north,ORDER[1],)wkt"
    R"wkt(ANGLEUNIT["degree",0.0174532925199433]],AXIS["geodetic longitude (Lon)",east,ORDER[2],)wkt"
    R"wkt(ANGLEUNIT["degree",0.0174532925199433]],AXIS["ellipsoidal height (h)",up,ORDER[3],)wkt"
    R"wkt(LENGTHUNIT["metre",1]],ID["EPSG",4979]])wkt";

bool is_shot_coordinate(std::string_view name) {
  return name == "shot" || name == "time" || name == "lat" || name == "lon";
}

nc_type nc_type_of(StorageType type) {
  switch (type) {
    case StorageType::int64:
      return NC_INT64;
    case StorageType::uint8:
      return NC_UBYTE;
    case StorageType::int32:
      return NC_INT;
    case StorageType::float32:
      return NC_FLOAT;
    case StorageType::float64:
      return NC_DOUBLE;
  }
  return NC_NAT;
}

}  // namespace

using shots_nc::copy_flat;
using shots_nc::describe_shape;
using shots_nc::has_shape;
using shots_nc::join_shape;

int NetcdfWriter::Impl::dim(const char* name) const {
  for (const Dimension& dimension : dims) {
    if (dimension.name == name) return dimension.id;
  }
  fail(std::string("internal: no dimension '") + name + "'");
}

void NetcdfWriter::Impl::define_dim(const char* name, std::size_t length) {
  int id = -1;
  check(nc_def_dim(nc.id(), name, length, &id), std::string("defining dimension '") + name + "'");
  dims.push_back({name, id, length});
}

void NetcdfWriter::Impl::put_text(int varid, const char* variable, const char* name,
                                  const std::string& value) const {
  check(nc_put_att_text(nc.id(), varid, name, value.size(), value.c_str()),
        std::string("attribute '") + name + "' of '" + variable + "'");
}

void NetcdfWriter::Impl::put_text_if(int varid, const char* variable, const char* name,
                                     const char* value) const {
  if (value != nullptr) put_text(varid, variable, name, value);
}

// A variable with the attributes every variable of the product has.
int NetcdfWriter::Impl::define_variable(const char* name, nc_type type,
                                        const std::vector<int>& dimids, const char* units,
                                        const char* long_name, const char* standard_name) const {
  int varid = -1;
  check(nc_def_var(nc.id(), name, type, static_cast<int>(dimids.size()), dimids.data(), &varid),
        std::string("defining variable '") + name + "'");
  put_text(varid, name, "units", units);
  put_text(varid, name, "long_name", long_name);
  put_text_if(varid, name, "standard_name", standard_name);
  return varid;
}

// NaN fill on floating-point data. Integer variables get no _FillValue: finish() refuses a
// product with a record never written, so they hold no fill, and xarray would turn a masked
// integer into float.
void NetcdfWriter::Impl::put_fill(int varid, const ProductField& def) const {
  const std::string what = std::string("variable '") + def.name + "' _FillValue";
  if (def.type == StorageType::float32) {
    const auto fill = static_cast<float>(def.fill);
    check(nc_put_att_float(nc.id(), varid, "_FillValue", NC_FLOAT, 1, &fill), what);
  } else if (def.type == StorageType::float64) {
    check(nc_put_att_double(nc.id(), varid, "_FillValue", NC_DOUBLE, 1, &def.fill), what);
  }
}

// Whole shots to a chunk, so that write() fills whole chunks (held until complete, in any
// order: no read-modify-write), compressed; returns the shots of a chunk.
std::size_t NetcdfWriter::Impl::chunk_by_shot(int varid, const ProductField& def,
                                              const std::vector<std::size_t>& lengths) const {
  const std::string what = std::string("variable '") + def.name + "'";
  std::size_t shot_B = def.type == StorageType::uint8                                       ? 1
                       : def.type == StorageType::int32 || def.type == StorageType::float32 ? 4
                                                                                            : 8;
  for (std::size_t n : lengths) shot_B *= n;
  std::size_t chunk_shots = kMostShotsPerChunk;
  while (chunk_shots > 1 && chunk_shots * shot_B > kChunkTarget_B) chunk_shots /= 2;
  chunk_shots = std::min(shots, chunk_shots);
  std::vector<std::size_t> chunks = {chunk_shots};
  chunks.insert(chunks.end(), lengths.begin(), lengths.end());
  check(nc_def_var_chunking(nc.id(), varid, NC_CHUNKED, chunks.data()), what + " chunking");
  check(nc_def_var_deflate(nc.id(), varid, 1, 1, kDeflateLevel), what + " compression");
  // Each chunk is written once, whole: with no room to cache it HDF5 compresses and writes it
  // then, beside the next batch's simulation, not all at once when the file closes (a bare slope
  // spent 12 % of its run there, on one thread, after the last shot). netCDF-C 4.9 takes a
  // cache of 0 bytes for "the file's default", so the cache is one byte: smaller than any chunk.
  check(nc_set_var_chunk_cache(nc.id(), varid, 1, 1, 1.0f), what + " chunk cache");
  return chunk_shots;
}

// The value HDF5 fills a variable with where nothing was written: its _FillValue, or
// netCDF's default for an integer type.
double NetcdfWriter::Impl::fill_of(int varid, const ProductField& def) const {
  int no_fill = 0;
  const std::string what = std::string("variable '") + def.name + "' fill value";
  if (def.type == StorageType::float32) {
    float fill = 0.0f;
    check(nc_inq_var_fill(nc.id(), varid, &no_fill, &fill), what);
    return fill;
  }
  if (def.type == StorageType::int32) {
    int fill = 0;
    check(nc_inq_var_fill(nc.id(), varid, &no_fill, &fill), what);
    return fill;
  }
  double fill = 0.0;
  if (def.type == StorageType::float64)
    check(nc_inq_var_fill(nc.id(), varid, &no_fill, &fill), what);
  return fill;
}

// A list a shot along `photon` (CF contiguous ragged array), chunked and compressed along it.
void NetcdfWriter::Impl::define_ragged_variable(const ProductField& def) {
  const int varid = define_variable(def.name, nc_type_of(def.type), {dim("photon")}, def.units,
                                    def.long_name, def.standard_name);
  put_text_if(varid, def.name, "comment", def.comment);
  put_fill(varid, def);
  const std::string what = std::string("variable '") + def.name + "'";
  const std::size_t chunk[] = {kPhotonsPerChunk};
  check(nc_def_var_chunking(nc.id(), varid, NC_CHUNKED, chunk), what + " chunking");
  check(nc_def_var_deflate(nc.id(), varid, 1, 1, kDeflateLevel), what + " compression");
  ragged.push_back({&def, varid});
}

// CF's count variable of the contiguous ragged arrays: photons a shot, in shot order.
void NetcdfWriter::Impl::define_photon_count() {
  photon_count = define_variable("photon_count", NC_INT, {dim("shot")}, "1",
                                 "number of photon events of the shot");
  put_text(photon_count, "photon_count", "sample_dimension", "photon");
}

void NetcdfWriter::Impl::define_shot_variable(const ProductField& def) {
  if (def.ragged()) {
    if (shape.photons) define_ragged_variable(def);
    return;
  }
  std::vector<std::size_t> lengths = shape.of(def);
  if (def.per_band() && lengths.empty()) return;  // this run has no such dimension
  std::vector<int> dimids = {dim("shot")};
  if (def.per_band()) dimids.push_back(dim("band"));
  for (const char* inner : def.inner_dims)
    if (inner != nullptr) dimids.push_back(dim(inner));

  const int varid = define_variable(def.name, nc_type_of(def.type), dimids, def.units,
                                    def.long_name, def.standard_name);
  put_text_if(varid, def.name, "comment", def.comment);
  put_text_if(varid, def.name, "gedi_name", def.gedi_name);
  put_text_if(varid, def.name, "glas_name", def.glas_name);
  put_fill(varid, def);
  if (!is_shot_coordinate(def.name)) {
    put_text(varid, def.name, "coordinates", kShotCoordinates);
    put_text(varid, def.name, "grid_mapping", kCrsVariable);
  }
  DefinedVariable variable{&def, varid, lengths};
  variable.chunk_shots = chunk_by_shot(varid, def, lengths);
  for (std::size_t n : lengths) variable.per_shot *= n;
  std::visit(
      [&](auto field) {
        using T = std::remove_cvref_t<decltype(ShotRecord{}.*field)>;
        if constexpr (std::is_same_v<T, std::int64_t>) variable.held = Held::int64s;
        if constexpr (std::is_same_v<T, std::uint8_t>) variable.held = Held::bytes;
      },
      def.field);
  variable.fill = fill_of(varid, def);
  variables.push_back(std::move(variable));
}

void NetcdfWriter::Impl::define_globals(const RunInfo& info) {
  const std::string title = "glaswave simulated satellite waveform lidar shots";
  const std::string source = std::string("glaswave ") + GLASWAVE_VERSION;
  put_text(NC_GLOBAL, "global", "Conventions", "CF-1.10, ACDD-1.3");
  put_text(NC_GLOBAL, "global", "featureType", "trajectory");
  put_text(NC_GLOBAL, "global", "title", title);
  put_text(NC_GLOBAL, "global", "summary",
           "Waveforms of a satellite laser altimeter (GLAS- or GEDI-like) simulated by Monte "
           "Carlo radiative transfer over terrain and vegetation, one record per shot, with "
           "their geolocation, GLA14- and GEDI L2A-style waveform metrics, and the truth of the "
           "simulated scene under each footprint.");
  put_text(NC_GLOBAL, "global", "keywords",
           "lidar, waveform lidar, laser altimetry, GLAS, ICESat, GEDI, canopy height, "
           "vegetation structure, Monte Carlo radiative transfer, simulation");
  put_text(NC_GLOBAL, "global", "standard_name_vocabulary", "CF Standard Name Table v84");
  put_text(NC_GLOBAL, "global", "processing_level", "simulated L1B/L2A-like waveforms");
  put_text(NC_GLOBAL, "global", "creator_name", "");
  put_text(NC_GLOBAL, "global", "date_created",
           info.created.iso8601.empty() ? product_creation_time().iso8601 : info.created.iso8601);
  put_text(NC_GLOBAL, "global", "history", info.command_line);
  put_text(NC_GLOBAL, "global", "source", source);
  put_text(
      NC_GLOBAL, "global", "references",
      "North et al. (2010), A Monte Carlo radiative transfer model of satellite waveform lidar");
  put_text(NC_GLOBAL, "global", "config", info.config_json);
  // The variables that every shot shares, as coordinates (xarray reads this attribute): runs
  // of parts of a track (`--shots`) then combine with xarray's defaults, which would otherwise
  // stack each part's copy of them along the shot dimension.
  put_text(NC_GLOBAL, "global", "coordinates",
           "trajectory crs wavelength band_name bin_time_ns tx_time_ns tx_waveform");
  if (!info.vertical_datum.empty())
    put_text(NC_GLOBAL, "global", "vertical_datum", info.vertical_datum);
  const unsigned long long seed = info.seed;
  check(nc_put_att_ulonglong(nc.id(), NC_GLOBAL, "seed", NC_UINT64, 1, &seed),
        "global attribute 'seed'");
}

void NetcdfWriter::Impl::define_dims() {
  define_dim("shot", shots);
  define_dim("band", shape.bands);
  define_dim("bin", shape.bins);
  define_dim("tx_bin", tx_bins);
  define_dim("gaussian", shape.length("gaussian"));
  define_dim("percentile", shape.length("percentile"));
  if (shape.orders > 0) define_dim("order", shape.orders);
  if (shape.photons) define_dim("photon", NC_UNLIMITED);
}

NetcdfWriter::Impl::RunVariables NetcdfWriter::Impl::define_run_variables() const {
  RunVariables v;
  // CF: a single trajectory is identified by a scalar variable with cf_role trajectory_id.
  v.trajectory =
      define_variable("trajectory", NC_STRING, {}, "1", "trajectory (the simulated track)");
  put_text(v.trajectory, "trajectory", "cf_role", "trajectory_id");
  // The band's coordinate is its wavelength, so that ds.sel(band=1064) picks a band;
  // `wavelength` says the same under the name it had first.
  v.band = define_variable("band", NC_DOUBLE, {dim("band")}, "nm", "laser wavelength of the band",
                           "sensor_band_central_radiation_wavelength");
  v.wavelength =
      define_variable("wavelength", NC_DOUBLE, {dim("band")}, "nm", "laser wavelength of the band",
                      "sensor_band_central_radiation_wavelength");
  v.band_name = define_variable("band_name", NC_STRING, {dim("band")}, "1", "name of the band");
  v.bin_time = define_variable("bin_time_ns", NC_DOUBLE, {dim("bin")}, "ns",
                               "time of each bin centre after the return from range_m (two-way)");
  v.tx_time = define_variable("tx_time_ns", NC_DOUBLE, {dim("tx_bin")}, "ns",
                              "time of each transmitted pulse bin centre about the pulse peak");
  v.tx_waveform = define_variable("tx_waveform", NC_FLOAT, {dim("band"), dim("tx_bin")}, "W",
                                  "transmitted pulse power");
  put_text(v.tx_waveform, "tx_waveform", "gedi_name", "txwaveform");
  v.crs = define_crs();
  if (shape.orders > 0)
    v.order = define_variable("order", NC_INT, {dim("order")}, "1", "scattering order");
  // The coordinate of rh's last dimension, so that ds.rh.sel(percentile=98) reads as GEDI's
  // rh98.
  v.percentile = define_variable("percentile", NC_INT, {dim("percentile")}, "percent",
                                 "percentage of energy_tr counted up from signal end");
  return v;
}

// CF's grid mapping of geodetic coordinates on WGS 84, heights above the ellipsoid.
int NetcdfWriter::Impl::define_crs() const {
  const int varid = define_variable(kCrsVariable, NC_INT, {}, "1",
                                    "coordinate reference system: WGS 84 "
                                    "(EPSG:4979), heights above the ellipsoid");
  put_text(varid, kCrsVariable, "grid_mapping_name", "latitude_longitude");
  put_text(varid, kCrsVariable, "crs_wkt", kCrsWkt);
  put_text(varid, kCrsVariable, "geographic_crs_name", "WGS 84");
  put_text(varid, kCrsVariable, "horizontal_datum_name", "World Geodetic System 1984");
  put_text(varid, kCrsVariable, "reference_ellipsoid_name", "WGS 84");
  put_text(varid, kCrsVariable, "prime_meridian_name", "Greenwich");
  const std::pair<const char*, double> numbers[] = {{"semi_major_axis", 6378137.0},
                                                    {"inverse_flattening", 298.257223563},
                                                    {"longitude_of_prime_meridian", 0.0}};
  for (const auto& [name, value] : numbers) {
    check(nc_put_att_double(nc.id(), varid, name, NC_DOUBLE, 1, &value),
          std::string("attribute '") + name + "' of 'crs'");
  }
  return varid;
}

void NetcdfWriter::Impl::put_flags(int varid, const char* variable,
                                   std::span<const unsigned char> values,
                                   const char* meanings) const {
  check(nc_put_att_uchar(nc.id(), varid, "flag_values", NC_UBYTE, values.size(), values.data()),
        std::string("attribute 'flag_values' of '") + variable + "'");
  put_text(varid, variable, "flag_meanings", meanings);
}

// The few attributes beyond those of the table.
void NetcdfWriter::Impl::define_special_attributes() const {
  for (const DefinedVariable& variable : variables) {
    if (std::string_view(variable.def->name) == "time")
      put_text(variable.varid, "time", "calendar", "standard");
    if (std::string_view(variable.def->name) == "quality_flag") {
      const unsigned char values[] = {quality_invalid, quality_good};
      put_flags(variable.varid, "quality_flag", values, "not_valid valid");
    }
    if (std::string_view(variable.def->name) == "quality_reason") {
      const unsigned char values[] = {reason_none, reason_off_terrain, reason_nodata,
                                      reason_no_signal, reason_low_signal};
      put_flags(variable.varid, "quality_reason", values,
                "none off_terrain nodata no_signal low_signal");
      put_text(variable.varid, "quality_reason", "comment",
               "off_terrain: the beam's axis met no terrain (off the DEM, or into a nodata "
               "hole); nodata: it met the terrain, but nodata or the DEM's edge lies within 3 "
               "sigma of the beam; no_signal: no band's waveform rises above its threshold; "
               "low_signal: no band's peak stands 8 noise sd above the noise. Values 5 and up "
               "are kept for more reasons found in the waveform (saturated).");
    }
  }
}

void NetcdfWriter::Impl::write_run_variables(const RunInfo& info, const RunVariables& v) const {
  const char* trajectory_id = "track";
  check(nc_put_var_string(nc.id(), v.trajectory, &trajectory_id), "writing variable 'trajectory'");
  std::vector<double> wavelengths;
  std::vector<const char*> names;
  for (const ProductBand& band : info.bands) {
    wavelengths.push_back(band.wavelength_nm);
    names.push_back(band.name.c_str());
  }
  check(nc_put_var_double(nc.id(), v.band, wavelengths.data()), "writing variable 'band'");
  check(nc_put_var_double(nc.id(), v.wavelength, wavelengths.data()),
        "writing variable 'wavelength'");
  check(nc_put_var_string(nc.id(), v.band_name, names.data()), "writing variable 'band_name'");
  check(nc_put_var_double(nc.id(), v.bin_time, info.bin_time_ns.data()),
        "writing variable 'bin_time_ns'");
  check(nc_put_var_double(nc.id(), v.tx_time, info.tx_time_ns.data()),
        "writing variable 'tx_time_ns'");
  std::vector<double> tx(shape.bands * tx_bins);
  const std::size_t tx_shape[] = {shape.bands, tx_bins};
  if (!has_shape(info.tx_waveform_W, tx_shape)) {
    fail("tx_waveform must be " + join_shape(tx_shape) + " (band x tx_bin), got " +
         describe_shape(info.tx_waveform_W));
  }
  copy_flat(info.tx_waveform_W, tx.data());
  check(nc_put_var_double(nc.id(), v.tx_waveform, tx.data()), "writing variable 'tx_waveform'");
  std::vector<int> percentiles;
  for (std::size_t k = 0; k < shape.length("percentile"); ++k)
    percentiles.push_back(static_cast<int>(k));
  check(nc_put_var_int(nc.id(), v.percentile, percentiles.data()), "writing variable 'percentile'");
  if (v.order >= 0) {
    std::vector<int> numbers;
    for (std::size_t o = 1; o <= shape.orders; ++o) numbers.push_back(static_cast<int>(o));
    check(nc_put_var_int(nc.id(), v.order, numbers.data()), "writing variable 'order'");
  }
}

void NetcdfWriter::Impl::define(const RunInfo& info) {
  reproducible = info.created.reproducible;
  define_globals(info);
  define_dims();
  const RunVariables run_variables = define_run_variables();
  for (const ProductField& def : product_fields()) define_shot_variable(def);
  if (shape.photons) define_photon_count();
  define_special_attributes();
  open_chunks.resize(variables.size());
  check(nc_enddef(nc.id()), "ending definitions");
  write_run_variables(info, run_variables);
}

}  // namespace glaswave
