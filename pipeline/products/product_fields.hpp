// The one table of the per-shot product fields (PRODUCT.md section 4). Each row says what a
// field is called, how it is stored, its CF attributes, where its value lives in ShotRecord,
// where that value comes from, and how it appears in footprints.geojson. The NetCDF and GeoJSON
// writers, the fill of a flagged shot and the copy of the waveform metrics into the record are
// all driven by it: a new field is one row.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "pipeline/products/shot_record.hpp"
#include "pipeline/products/waveform_metrics.hpp"

namespace glaswave {

// How a field is stored in shots.nc; values are converted by the netCDF library.
enum class StorageType : std::uint8_t { int64, uint8, int32, float32, float64 };

// Where a field's value comes from. It decides what a flagged shot (no waveform) carries.
enum class FieldSource : std::uint8_t {
  shot,         // the track and the run: number, time, spacecraft, pointing, flag; always known
  geolocation,  // the footprint on the terrain: fill, the engine puts back what it still knows
  simulation,   // the transport's waveforms and energies: fill
  metrics,      // the waveform processing (the `metric` column): fill
  truth,        // the scene's truth over the footprint: fill
};

// How a field appears among a footprint's GeoJSON properties.
enum class GeojsonProperty : std::uint8_t {
  none,    // not there (arrays over bins and Gaussians)
  value,   // the value under the field's name; a per-band field gives every band's, each under
           // the name suffixed with the band's (energy_tr_1064, reflectance_532)
  levels,  // a few entries of the last dimension, as GEDI names them (rh25 ... rh100), each
           // band's suffixed as above (rh98_1064)
};

// The ShotRecord member a field lives in. Nested vectors are [band][...].
using RecordField =
    std::variant<std::int64_t ShotRecord::*, std::uint8_t ShotRecord::*, double ShotRecord::*,
                 std::vector<double> ShotRecord::*, std::vector<std::int32_t> ShotRecord::*,
                 std::vector<std::vector<double>> ShotRecord::*,
                 std::vector<std::vector<std::vector<double>>> ShotRecord::*>;

// The WaveformMetrics member a per-band metrics field is copied from.
using MetricField = std::variant<std::monostate, double WaveformMetrics::*, int WaveformMetrics::*,
                                 std::array<double, kMaxGaussians> WaveformMetrics::*,
                                 std::array<double, kRhLevels> WaveformMetrics::*>;

struct ProductField {
  const char* name;
  StorageType type;
  RecordField field;
  FieldSource source;
  const char* units;
  const char* long_name;
  const char* standard_name = nullptr;  // only where CF has one
  // Dimensions after (shot, band) of an array field: "bin", "order", "gaussian", "percentile".
  // A field whose dimension a run lacks (`order` without per-order output) is left out.
  // "photon" alone makes a variable-length field: a list a shot (ragged()).
  std::array<const char*, 2> inner_dims = {nullptr, nullptr};
  const char* comment = nullptr;    // how a derived quantity is defined
  const char* gedi_name = nullptr;  // the GEDI L1B/L2A equivalent, where there is one
  const char* glas_name = nullptr;  // the GLAH14 equivalent, where there is one
  // What a flagged shot carries, and the NetCDF _FillValue of a floating-point field.
  double fill = std::numeric_limits<double>::quiet_NaN();
  MetricField metric = {};
  GeojsonProperty geojson = GeojsonProperty::value;
  // Only in a run with an `atmosphere` section (ProductShape::atmosphere): other runs' products
  // keep their variables and bits.
  bool atmosphere_only = false;

  // True for [band]... fields; false for per-shot scalars and ragged fields.
  bool per_band() const;
  // True for a variable-length field: each shot's list of values along the `photon`
  // dimension, stored as a CF contiguous ragged array (CF 1.10 section 9.3.3, appendix H.2.4)
  // counted by photon_count; only in a run whose records carry photon events.
  bool ragged() const;
};

// The rows, in the order of shots.nc's variables.
std::span<const ProductField> product_fields();

// The row named `name`, or nullptr.
const ProductField* find_product_field(std::string_view name);

// GEDI L2A's usual few of rh0..rh100, the GeoJSON properties of a `levels` field.
inline constexpr std::array<int, 5> kGeojsonLevels = {25, 50, 75, 98, 100};

// One GeoJSON property: its name, the band it reads (0 for a per-shot scalar) and, for a
// `levels` field, the entry of the last dimension (kGeojsonLevels).
struct GeojsonPropertyName {
  std::string name;
  std::size_t band = 0;
  int level = -1;  // -1 unless the field is `levels`
};

// The GeoJSON properties of `field`, in order: none; one for a per-shot scalar; one per band
// (and per level, band after band) for a per-band field, named with the band's name as a
// suffix ("energy_tr_1064", "rh98_532"). `band_names` are the run's (RunInfo::bands).
std::vector<GeojsonPropertyName> geojson_properties(const ProductField& field,
                                                    const std::vector<std::string>& band_names);

// The lengths of a run's dimensions after (shot, band).
struct ProductShape {
  std::size_t bands = 0;
  std::size_t bins = 0;
  std::size_t orders = 0;   // 0 without per-order output
  bool photons = false;     // the records carry photon events
  bool atmosphere = false;  // the run has an `atmosphere` section

  // Length of dimension `name` ("bin", "order", "gaussian", "percentile"); 0 when the run
  // has none.
  std::size_t length(std::string_view name) const;
  // [band] then the inner dimensions of `field`; empty for a scalar, a ragged field or a field
  // the run lacks (a dimension, or its atmosphere).
  std::vector<std::size_t> of(const ProductField& field) const;
};

// Sets every field of `source` to its fill, shaped as `shape` says (a field the run lacks is
// emptied).
void fill_fields(ShotRecord& record, FieldSource source, const ProductShape& shape);

// A shot that has no waveform (off the DEM, over nodata): every field that does not come from
// the shot itself is fill. The caller sets the flag and puts back the position it knows.
void fill_flagged(ShotRecord& record, const ProductShape& shape);

// Copies band `band` of the metrics fields from `metrics`; the record's metrics fields must
// already be shaped (fill_fields with FieldSource::metrics).
void store_metrics(ShotRecord& record, std::size_t band, const WaveformMetrics& metrics);

}  // namespace glaswave
