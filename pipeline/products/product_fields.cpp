// The product field table and what it drives outside the writers: the shapes of a run's
// fields, the fill of a flagged shot, and the copy of the waveform metrics into the record.
#include "pipeline/products/product_fields.hpp"

#include <stdexcept>
#include <type_traits>

namespace glaswave {
namespace {

using S = StorageType;
using F = FieldSource;
using R = ShotRecord;
using M = WaveformMetrics;

// Spacecraft latitude/longitude carry no standard_name on purpose: tools that find the
// geolocation by standard_name must find the footprint, not the spacecraft.
const ProductField kProductFields[] = {
    // The coordinate of the shot dimension, so that runs of parts of a track (`--shots`)
    // combine by coordinates into the whole track; shot_number says the same for GEDI's readers.
    {.name = "shot",
     .type = S::int64,
     .field = &R::shot_number,
     .source = F::shot,
     .units = "1",
     .long_name = "shot number in the track, from 0 (unique in the track)",
     .geojson = GeojsonProperty::none},
    {.name = "shot_number",
     .type = S::int64,
     .field = &R::source_shot_number,
     .source = F::shot,
     .units = "1",
     .long_name = "the instrument's shot number: a granule track's own (GEDI shot_number, GLAH14 "
                  "i_rec_ndx * 40 + i_shot_count - 1), else the shot in the track, from 0",
     .gedi_name = "shot_number",
     .glas_name = "i_rec_ndx"},
    {.name = "time",
     .type = S::float64,
     .field = &R::time_s,
     .source = F::shot,
     .units = "seconds since 2000-01-01 12:00:00",
     .long_name = "time of the shot (seconds since the GLAS epoch)",
     .standard_name = "time",
     .gedi_name = "delta_time",
     .glas_name = "d_UTCTime_40"},
    {.name = "lat",
     .type = S::float64,
     .field = &R::lat_deg,
     .source = F::geolocation,
     .units = "degrees_north",
     .long_name = "latitude of the footprint centre on the terrain",
     .standard_name = "latitude",
     .gedi_name = "lat_lowestmode",
     .glas_name = "d_lat"},
    {.name = "lon",
     .type = S::float64,
     .field = &R::lon_deg,
     .source = F::geolocation,
     .units = "degrees_east",
     .long_name = "longitude of the footprint centre on the terrain",
     .standard_name = "longitude",
     .gedi_name = "lon_lowestmode",
     .glas_name = "d_lon"},
    {.name = "elev",
     .type = S::float64,
     .field = &R::elev_m,
     .source = F::geolocation,
     .units = "m",
     .long_name = "elevation of the footprint centre above the WGS84 ellipsoid",
     .standard_name = "height_above_reference_ellipsoid",
     .gedi_name = "digital_elevation_model",
     .glas_name = "d_DEM_elv"},
    {.name = "sc_lat",
     .type = S::float64,
     .field = &R::sc_lat_deg,
     .source = F::shot,
     .units = "degrees_north",
     .long_name = "latitude of the spacecraft"},
    {.name = "sc_lon",
     .type = S::float64,
     .field = &R::sc_lon_deg,
     .source = F::shot,
     .units = "degrees_east",
     .long_name = "longitude of the spacecraft"},
    {.name = "sc_alt",
     .type = S::float64,
     .field = &R::sc_alt_m,
     .source = F::shot,
     .units = "m",
     .long_name = "altitude of the spacecraft above the WGS84 ellipsoid"},
    {.name = "off_nadir_deg",
     .type = S::float64,
     .field = &R::off_nadir_deg,
     .source = F::shot,
     .units = "degree",
     .long_name = "angle between the laser pointing and geodetic nadir"},
    {.name = "range_m",
     .type = S::float64,
     .field = &R::range_m,
     .source = F::geolocation,
     .units = "m",
     .long_name = "range from the spacecraft to the footprint centre"},
    {.name = "slope_deg",
     .type = S::float64,
     .field = &R::slope_deg,
     .source = F::geolocation,
     .units = "degree",
     .long_name = "terrain slope over the footprint",
     .standard_name = "ground_slope_angle"},
    {.name = "aspect_deg",
     .type = S::float64,
     .field = &R::aspect_deg,
     .source = F::geolocation,
     .units = "degree",
     .long_name =
         "terrain aspect over the footprint (direction the slope faces, clockwise from north)",
     .standard_name = "ground_slope_direction"},
    {.name = "elev_bin0",
     .type = S::float64,
     .field = &R::elev_bin0_m,
     .source = F::geolocation,
     .units = "m",
     .long_name =
         "elevation of the first waveform bin (nearest the spacecraft) above the WGS84 ellipsoid",
     .standard_name = "height_above_reference_ellipsoid",
     .gedi_name = "geolocation/elevation_bin0"},
    {.name = "elev_lastbin",
     .type = S::float64,
     .field = &R::elev_lastbin_m,
     .source = F::geolocation,
     .units = "m",
     .long_name = "elevation of the last waveform bin above the WGS84 ellipsoid",
     .standard_name = "height_above_reference_ellipsoid",
     .gedi_name = "geolocation/elevation_lastbin"},
    {.name = "quality_flag",
     .type = S::uint8,
     .field = &R::quality_flag,
     .source = F::shot,
     .units = "1",
     .long_name = "1 for a valid waveform, 0 for none (quality_reason says why)",
     .standard_name = "quality_flag",
     .gedi_name = "quality_flag"},
    {.name = "quality_reason",
     .type = S::uint8,
     .field = &R::quality_reason,
     .source = F::shot,
     .units = "1",
     .long_name = "why the shot has no valid waveform (0 when it has one)",
     .geojson = GeojsonProperty::none},
    {.name = "beam",
     .type = S::uint8,
     .field = &R::beam,
     .source = F::shot,
     .units = "1",
     .long_name = "the GEDI beam of a granule track's shot, by number (BEAM0101 is 5; 0 to 3 are "
                  "coverage beams of half the pulse energy); on an ICESat-2 pass, ATLAS's spot "
                  "number (1 to 6; gt1l to gt3r are 5, 6, 3, 4, 1, 2); 255 for other tracks",
     .gedi_name = "beam"},
    {.name = "degrade_flag",
     .type = S::uint8,
     .field = &R::degrade_flag,
     .source = F::shot,
     .units = "1",
     .long_name =
         "a GEDI granule track's degrade_flag, as the granule gives it; 0 for other tracks",
     .gedi_name = "geolocation/degrade_flag"},
    {.name = "solar_elevation",
     .type = S::float32,
     .field = &R::solar_elevation_deg,
     .source = F::shot,
     .units = "degree",
     .long_name = "the sun's elevation above the horizon at the footprint, geometric (ERFA)",
     .gedi_name = "geolocation/solar_elevation"},
    {.name = "solar_azimuth",
     .type = S::float32,
     .field = &R::solar_azimuth_deg,
     .source = F::shot,
     .units = "degree",
     .long_name = "the sun's azimuth at the footprint, clockwise from north (ERFA)",
     .gedi_name = "geolocation/solar_azimuth"},
    {.name = "rx_waveform",
     .type = S::float32,
     .field = &R::rx_waveform_W,
     .source = F::simulation,
     .units = "W",
     .long_name = "received power",
     .inner_dims = {"bin"},
     .gedi_name = "rxwaveform",
     .geojson = GeojsonProperty::none},
    {.name = "rx_waveform_canopy",
     .type = S::float32,
     .field = &R::rx_waveform_canopy_W,
     .source = F::simulation,
     .units = "W",
     .long_name = "received power whose last scattering was on vegetation",
     .inner_dims = {"bin"},
     .geojson = GeojsonProperty::none},
    {.name = "rx_waveform_ground",
     .type = S::float32,
     .field = &R::rx_waveform_ground_W,
     .source = F::simulation,
     .units = "W",
     .long_name = "received power whose last scattering was on the ground",
     .inner_dims = {"bin"},
     .geojson = GeojsonProperty::none},
    {.name = "rx_waveform_order",
     .type = S::float32,
     .field = &R::rx_waveform_order_W,
     .source = F::simulation,
     .units = "W",
     .long_name = "received power by scattering order",
     .inner_dims = {"order", "bin"},
     .geojson = GeojsonProperty::none},
    {.name = "rx_energy",
     .type = S::float64,
     .field = &R::rx_energy_J,
     .source = F::simulation,
     .units = "J",
     .long_name = "received energy (integral of rx_waveform)",
     .gedi_name = "rx_energy"},
    {.name = "rx_energy_canopy",
     .type = S::float64,
     .field = &R::rx_energy_canopy_J,
     .source = F::simulation,
     .units = "J",
     .long_name = "received energy whose last scattering was on vegetation (integral of "
                  "rx_waveform_canopy)"},
    {.name = "rx_energy_ground",
     .type = S::float64,
     .field = &R::rx_energy_ground_J,
     .source = F::simulation,
     .units = "J",
     .long_name = "received energy whose last scattering was on the ground (integral of "
                  "rx_waveform_ground)"},
    {.name = "reflectance",
     .type = S::float64,
     .field = &R::reflectance,
     .source = F::simulation,
     .units = "1",
     .long_name = "surface reflectance from the waveform, pi E_rec R^2 / (E_trans A_t T_atm) "
                  "(North et al. 2010, eq. 1)",
     .comment = "corrected for the atmosphere (T_atm); GLAH14's Data_40HZ/Reflectivity/d_reflctUC "
                "is not: it is this times the band's atmos_transmission_roundtrip (glah14.h5 "
                "writes it)"},
    // Waveform processing (pipeline/products/waveform_metrics.hpp states the rules).
    {.name = "energy_tr",
     .type = S::float64,
     .field = &R::energy_tr_J,
     .source = F::metrics,
     .units = "J",
     .long_name = "total return: energy above the noise between signal begin and end (seed TR)",
     .comment = "energy_tr = energy_cr + energy_gr",
     .metric = &M::energy_tr_J},
    {.name = "energy_cr",
     .type = S::float64,
     .field = &R::energy_cr_J,
     .source = F::metrics,
     .units = "J",
     .long_name = "canopy return: the part of energy_tr above the canopy/ground split (seed CR)",
     .comment = "split 4 sigma of the lowest Gaussian above its centre, or lower where the other "
                "Gaussians outweigh it",
     .metric = &M::energy_cr_J},
    {.name = "energy_gr",
     .type = S::float64,
     .field = &R::energy_gr_J,
     .source = F::metrics,
     .units = "J",
     .long_name = "ground return: the part of energy_tr below the canopy/ground split (seed GR)",
     .metric = &M::energy_gr_J},
    {.name = "waveform_index",
     .type = S::float64,
     .field = &R::waveform_index,
     .source = F::metrics,
     .units = "1",
     .long_name = "waveform index (CR - GR) / (CR + GR) (North et al. 2010, eq. 3)",
     .metric = &M::waveform_index},
    {.name = "sig_begin_m",
     .type = S::float64,
     .field = &R::sig_begin_m,
     .source = F::metrics,
     .units = "m",
     .long_name =
         "elevation of signal begin: first crossing of the threshold by the smoothed waveform",
     .standard_name = "height_above_reference_ellipsoid",
     .comment = "threshold = noise mean + max(4 noise sd, 0.01 (peak - noise mean)) on the "
                "waveform smoothed with the pulse's width",
     .glas_name = "d_SigBegOff",
     .metric = &M::sig_begin_m},
    {.name = "sig_end_m",
     .type = S::float64,
     .field = &R::sig_end_m,
     .source = F::metrics,
     .units = "m",
     .long_name =
         "elevation of signal end: last crossing of the threshold by the smoothed waveform",
     .standard_name = "height_above_reference_ellipsoid",
     .glas_name = "d_SigEndOff",
     .metric = &M::sig_end_m},
    {.name = "centroid_m",
     .type = S::float64,
     .field = &R::centroid_m,
     .source = F::metrics,
     .units = "m",
     .long_name = "elevation of the waveform's centroid between signal begin and end",
     .standard_name = "height_above_reference_ellipsoid",
     .glas_name = "d_elev",
     .metric = &M::centroid_m},
    // No peaks, not fill, on a flagged shot: the count is known to be none.
    {.name = "n_peaks",
     .type = S::int32,
     .field = &R::n_peaks,
     .source = F::metrics,
     .units = "1",
     .long_name = "number of Gaussians fitted to the waveform",
     .gedi_name = "num_detectedmodes",
     .glas_name = "i_numPk",
     .fill = 0.0,
     .metric = &M::n_peaks},
    {.name = "gauss_amp",
     .type = S::float64,
     .field = &R::gauss_amp_W,
     .source = F::metrics,
     .units = "W",
     .long_name = "amplitude of each fitted Gaussian",
     .inner_dims = {"gaussian"},
     .glas_name = "d_Gamp",
     .metric = &M::gauss_amp_W,
     .geojson = GeojsonProperty::none},
    {.name = "gauss_center_m",
     .type = S::float64,
     .field = &R::gauss_center_m,
     .source = F::metrics,
     .units = "m",
     .long_name =
         "elevation of the centre of each fitted Gaussian (in waveform order, highest first)",
     .standard_name = "height_above_reference_ellipsoid",
     .inner_dims = {"gaussian"},
     .glas_name = "d_gpCntRngOff",
     .metric = &M::gauss_center_m,
     .geojson = GeojsonProperty::none},
    {.name = "gauss_sigma_ns",
     .type = S::float64,
     .field = &R::gauss_sigma_ns,
     .source = F::metrics,
     .units = "ns",
     .long_name = "standard deviation of each fitted Gaussian",
     .inner_dims = {"gaussian"},
     .glas_name = "d_Gsigma",
     .metric = &M::gauss_sigma_ns,
     .geojson = GeojsonProperty::none},
    {.name = "gauss_area",
     .type = S::float64,
     .field = &R::gauss_area_J,
     .source = F::metrics,
     .units = "J",
     .long_name = "energy of each fitted Gaussian (its integral)",
     .inner_dims = {"gaussian"},
     .glas_name = "d_Garea",
     .metric = &M::gauss_area_J,
     .geojson = GeojsonProperty::none},
    {.name = "ground_elev_est",
     .type = S::float64,
     .field = &R::ground_elev_est_m,
     .source = F::metrics,
     .units = "m",
     .long_name = "ground elevation estimated from the waveform: centre of the lowest Gaussian",
     .standard_name = "height_above_reference_ellipsoid",
     .gedi_name = "elev_lowestmode",
     .metric = &M::ground_elev_m},
    {.name = "canopy_height_est",
     .type = S::float64,
     .field = &R::canopy_height_est_m,
     .source = F::metrics,
     .units = "m",
     .long_name = "canopy height estimated from the waveform: signal begin above ground_elev_est",
     .standard_name = "canopy_height",
     .comment = "as GLA14: it includes the pulse's own rise to the threshold (about 3.2 m over "
                "bare ground for a 5 ns pulse without noise); equal to rh100",
     .metric = &M::canopy_height_m},
    {.name = "rh",
     .type = S::float32,
     .field = &R::rh_m,
     .source = F::metrics,
     .units = "m",
     .long_name = "relative height above ground_elev_est at which the energy counted up from "
                  "signal end reaches percentile % of energy_tr (GEDI L2A)",
     .inner_dims = {"percentile"},
     .gedi_name = "rh",
     .metric = &M::rh_m,
     .geojson = GeojsonProperty::levels},
    {.name = "cover_true",
     .type = S::float64,
     .field = &R::cover_true,
     .source = F::truth,
     .units = "1",
     .long_name = "crown cover over the footprint, weighted by the beam (simulation truth)",
     .standard_name = "vegetation_area_fraction"},
    {.name = "pai_true",
     .type = S::float64,
     .field = &R::pai_true,
     .source = F::truth,
     .units = "1",
     .long_name = "plant area index over the footprint, weighted by the beam (simulation truth)"},
    {.name = "canopy_height_true",
     .type = S::float64,
     .field = &R::canopy_height_true_m,
     .source = F::truth,
     .units = "m",
     .long_name = "highest vegetation above the ground over the footprint (simulation truth)",
     .standard_name = "canopy_height"},
    {.name = "pgap_true",
     .type = S::float64,
     .field = &R::pgap_true,
     .source = F::truth,
     .units = "1",
     .long_name = "gap probability looking down vertically through the vegetation, weighted by "
                  "the beam (simulation truth): one less GEDI L2B's canopy cover"},
    // The atmosphere's truth (PRODUCT.md section 12): only with an `atmosphere` section.
    {.name = "atmosphere_transmission",
     .type = S::float64,
     .field = &R::atmosphere_transmission,
     .source = F::simulation,
     .units = "1",
     .long_name = "two-way direct transmission of the atmosphere's layers along the beam axis "
                  "(simulation truth)",
     .comment = "exp(-2 tau / mu): tau the layers' vertical extinction optical depth above the "
                "scene, mu the cosine of the beam axis from the local vertical; light the layers "
                "scatter forward into the field of view comes back beside it "
                "(atmosphere_scattered_fraction)",
     .geojson = GeojsonProperty::none,
     .atmosphere_only = true},
    {.name = "atmosphere_scattered_fraction",
     .type = S::float64,
     .field = &R::atmosphere_scattered_fraction,
     .source = F::simulation,
     .units = "1",
     .long_name = "part of the energy returned in the window whose light the atmosphere's layers "
                  "scattered, on the way down or back (simulation truth)",
     .geojson = GeojsonProperty::none,
     .atmosphere_only = true},
    {.name = "atmosphere_delay_m",
     .type = S::float64,
     .field = &R::atmosphere_delay_m,
     .source = F::simulation,
     .units = "m",
     .long_name = "energy-weighted extra path of the return from scattering in the atmosphere's "
                  "layers (simulation truth)",
     .comment = "over all the energy returned in the window, the unscattered light counting 0: "
                "the light's path less the straight way to the point it returned from and back; "
                "from orbit the return's mean range is late by half of it",
     .geojson = GeojsonProperty::none,
     .atmosphere_only = true},
    // A photon-counting receiver's events, a list a shot (ragged along `photon`).
    {.name = "photon_time",
     .type = S::float64,
     .field = &R::photon_time_ns,
     .source = F::simulation,
     .units = "ns",
     .long_name = "time of the detected photon after the return from range_m (two-way)",
     .inner_dims = {"photon", nullptr},
     .geojson = GeojsonProperty::none},
    {.name = "photon_lat",
     .type = S::float64,
     .field = &R::photon_lat_deg,
     .source = F::simulation,
     .units = "degrees_north",
     .long_name = "latitude of the detected photon's last scattering",
     .inner_dims = {"photon", nullptr},
     .geojson = GeojsonProperty::none},
    {.name = "photon_lon",
     .type = S::float64,
     .field = &R::photon_lon_deg,
     .source = F::simulation,
     .units = "degrees_east",
     .long_name = "longitude of the detected photon's last scattering",
     .inner_dims = {"photon", nullptr},
     .geojson = GeojsonProperty::none},
    {.name = "photon_h",
     .type = S::float64,
     .field = &R::photon_h_m,
     .source = F::simulation,
     .units = "m",
     .long_name = "height of the detected photon's last scattering above the WGS 84 ellipsoid",
     .inner_dims = {"photon", nullptr},
     .geojson = GeojsonProperty::none},
    {.name = "photon_class",
     .type = S::uint8,
     .field = &R::photon_class,
     .source = F::simulation,
     .units = "1",
     .long_name =
         "what the detected photon came from: 0 noise, 1 ground, 2 canopy, 3 top of canopy "
         "(truth)",
     .inner_dims = {"photon", nullptr},
     .geojson = GeojsonProperty::none},
    {.name = "photon_order",
     .type = S::uint8,
     .field = &R::photon_order,
     .source = F::simulation,
     .units = "1",
     .long_name = "scattering order of the detected photon's light, 0 for noise (truth)",
     .inner_dims = {"photon", nullptr},
     .geojson = GeojsonProperty::none},
};

template <class T>
constexpr bool is_scalar_member = std::is_arithmetic_v<T>;

// Resizes a [band][...] field to `shape` with every value `fill`.
void shape_fill(std::vector<double>& values, std::span<const std::size_t> shape, double fill) {
  values.assign(shape[0], fill);
}
void shape_fill(std::vector<std::int32_t>& values, std::span<const std::size_t> shape,
                double fill) {
  values.assign(shape[0], static_cast<std::int32_t>(fill));
}
template <class T>
void shape_fill(std::vector<std::vector<T>>& values, std::span<const std::size_t> shape,
                double fill) {
  values.resize(shape[0]);
  for (auto& inner : values) shape_fill(inner, shape.subspan(1), fill);
}

}  // namespace

bool ProductField::ragged() const {
  return inner_dims[0] != nullptr && std::string_view(inner_dims[0]) == "photon";
}

bool ProductField::per_band() const {
  if (ragged()) return false;
  return std::visit(
      [](auto member) {
        using T = std::remove_cvref_t<decltype(std::declval<ShotRecord>().*member)>;
        return !is_scalar_member<T>;
      },
      field);
}

std::span<const ProductField> product_fields() { return kProductFields; }

const ProductField* find_product_field(std::string_view name) {
  for (const ProductField& field : kProductFields)
    if (name == field.name) return &field;
  return nullptr;
}

std::vector<GeojsonPropertyName> geojson_properties(const ProductField& field,
                                                    const std::vector<std::string>& band_names) {
  std::vector<GeojsonPropertyName> properties;
  if (field.geojson == GeojsonProperty::none) return properties;
  if (!field.per_band()) {
    properties.push_back({field.name, 0, -1});
    return properties;
  }
  for (std::size_t band = 0; band < band_names.size(); ++band) {
    const std::string suffix = "_" + band_names[band];
    if (field.geojson == GeojsonProperty::levels) {
      for (const int level : kGeojsonLevels)
        properties.push_back({field.name + std::to_string(level) + suffix, band, level});
    } else {
      properties.push_back({field.name + suffix, band, -1});
    }
  }
  return properties;
}

std::size_t ProductShape::length(std::string_view name) const {
  if (name == "bin") return bins;
  if (name == "order") return orders;
  if (name == "gaussian") return kMaxGaussians;
  if (name == "percentile") return kRhLevels;
  throw std::logic_error("internal: unknown product dimension '" + std::string(name) + "'");
}

std::vector<std::size_t> ProductShape::of(const ProductField& field) const {
  if (!field.per_band()) return {};  // a scalar, or a list of any length
  if (field.atmosphere_only && !atmosphere) return {};
  std::vector<std::size_t> shape = {bands};
  for (const char* inner : field.inner_dims) {
    if (inner == nullptr) continue;
    const std::size_t n = length(inner);
    if (n == 0) return {};
    shape.push_back(n);
  }
  return shape;
}

void fill_fields(ShotRecord& record, FieldSource source, const ProductShape& shape) {
  for (const ProductField& field : kProductFields) {
    if (field.source != source) continue;
    const std::vector<std::size_t> lengths = shape.of(field);
    std::visit(
        [&](auto member) {
          auto& value = record.*member;
          using T = std::remove_cvref_t<decltype(value)>;
          if constexpr (is_scalar_member<T>) {
            value = static_cast<T>(field.fill);
          } else if (lengths.empty()) {
            value.clear();  // a dimension this run does not have
          } else {
            shape_fill(value, lengths, field.fill);
          }
        },
        field.field);
  }
}

void fill_flagged(ShotRecord& record, const ProductShape& shape) {
  for (const FieldSource source : {FieldSource::geolocation, FieldSource::simulation,
                                   FieldSource::metrics, FieldSource::truth})
    fill_fields(record, source, shape);
}

void store_metrics(ShotRecord& record, std::size_t band, const WaveformMetrics& metrics) {
  for (const ProductField& field : kProductFields) {
    if (field.source != FieldSource::metrics) continue;
    std::visit(
        [&](auto to, auto from) {
          using From = decltype(from);
          if constexpr (std::is_same_v<From, std::monostate>) {
            throw std::logic_error(std::string("internal: metrics field '") + field.name +
                                   "' names no metric");
          } else {
            auto& target = record.*to;
            const auto& value = metrics.*from;
            using T = std::remove_cvref_t<decltype(target)>;
            using V = std::remove_cvref_t<decltype(value)>;
            if constexpr (std::is_same_v<T, std::vector<double>> && std::is_same_v<V, double>) {
              target[band] = value;
            } else if constexpr (std::is_same_v<T, std::vector<std::int32_t>> &&
                                 std::is_same_v<V, int>) {
              target[band] = value;
            } else if constexpr (std::is_same_v<T, std::vector<std::vector<double>>> &&
                                 !std::is_arithmetic_v<V>) {
              target[band].assign(value.begin(), value.end());
            } else {
              throw std::logic_error(std::string("internal: metrics field '") + field.name +
                                     "' does not match its metric");
            }
          }
        },
        field.field, field.metric);
  }
}

}  // namespace glaswave
