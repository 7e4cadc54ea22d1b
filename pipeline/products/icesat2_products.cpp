// The ATL03- and ATL08-like granules, written through the one HDF5 layer (core/hdf5_file.hpp): no
// object time stamps, so that the same photons give the same bytes.
#include "pipeline/products/icesat2_products.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <type_traits>
#include <utility>
#include <variant>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/glas_time.hpp"
#include "core/hdf5_file.hpp"
#include "core/netcdf_lock.hpp"
#include "pipeline/products/atl03_platform_fields.hpp"

namespace glaswave {
namespace {

constexpr float fill_float = std::numeric_limits<float>::max();  // ATL08's 3.4028235e+38
constexpr double segment_20m = 20.0;

// A dataset's attributes, as the data dictionaries give them: units, long_name, contentType
// (physicalMeasurement, referenceInformation, modelResult, qualityInformation,
// auxiliaryInformation) and a description (where the simulation's value comes from).
struct Meta {
  std::string units, long_name, content_type, description;
};

// A group of the granule, named by its path.
class Group {
 public:
  explicit Group(std::string path) : path_(std::move(path)) {}
  const std::string& get() const { return path_; }

 private:
  std::string path_;
};

// A granule written under FINAL.part through the one HDF5 layer (core/hdf5_file.hpp), renamed
// when finished.
class Granule {
 public:
  explicit Granule(const std::filesystem::path& path)
      : file_(path), h5_(file_.part_path(), Hdf5Chunking::every) {}

  const std::string& file() const { return root_; }

  Group group(const std::string& parent, const std::string& name) {
    Group g(parent == "/" ? "/" + name : parent + "/" + name);
    h5_.group(g.get());
    return g;
  }

  // A dataset of `rows` x `columns` (columns 0: one dimension) with its attributes; with
  // `fill`, the type's largest value is its _FillValue (the products' 3.4028235e+38 for
  // float32, 127 for int8).
  template <typename T>
  void dataset(const std::string& parent, const std::string& name, const std::vector<T>& values,
               const Meta& meta, std::size_t columns = 0, bool fill = false) {
    std::vector<std::uint64_t> dims;
    if (columns) dims = {values.size() / columns, columns};
    std::optional<T> fill_value;
    if (fill) fill_value = std::numeric_limits<T>::max();
    h5_.write(parent + "/" + name, values, attributes(meta), dims, fill_value);
  }

  // A one-dimensional dataset whose _FillValue is `fill` (ph_index_beg's 0).
  template <typename T>
  void dataset_filled(const std::string& parent, const std::string& name,
                      const std::vector<T>& values, const Meta& meta, T fill) {
    h5_.write(parent + "/" + name, values, attributes(meta), {}, std::optional<T>(fill));
  }

  // A one-element dataset of fixed-length text (ancillary_data's UTC times).
  void text_dataset(const std::string& parent, const std::string& name, const std::string& text,
                    const Meta& meta) {
    h5_.write_text(parent + "/" + name, text, attributes(meta));
  }

  void text_attribute(const std::string& object, const std::string& name, const std::string& text) {
    h5_.text_attribute(object, name, text);
  }

  void ancillary(const GranuleInfo& info, const std::string& short_name,
                 const std::vector<BeamTrack>& beams);

  void finish() {
    h5_.close();
    file_.commit();
  }

 private:
  static std::vector<Hdf5Attribute> attributes(const Meta& meta) {
    std::vector<Hdf5Attribute> list{{"units", meta.units}, {"long_name", meta.long_name}};
    if (!meta.content_type.empty()) list.push_back({"contentType", meta.content_type});
    if (!meta.description.empty()) list.push_back({"description", meta.description});
    return list;
  }

  AtomicFile file_;
  Hdf5Writer h5_;
  std::string root_ = "/";
};

const Meta delta_time_meta{"seconds since 2018-01-01", "Elapsed GPS seconds",
                           "referenceInformation",
                           "Seconds since the ATLAS Standard Data Product epoch, "
                           "ancillary_data/atlas_sdp_gps_epoch GPS seconds after the GPS epoch"};

// A field of the simulation's truth, in no real product.
Meta truth_meta(const std::string& units, const std::string& long_name) {
  return {units, long_name, "modelResult", "glaswave's own: the simulation's truth"};
}

// The first and last shot times of all beams (the ATLAS epoch when there is none).
std::pair<double, double> time_span(const std::vector<BeamTrack>& beams) {
  double first = std::numeric_limits<double>::infinity(), last = -first;
  for (const BeamTrack& beam : beams)
    for (const BeamShot& shot : beam.shots) {
      first = std::min(first, shot.delta_time_s);
      last = std::max(last, shot.delta_time_s);
    }
  if (first > last) first = last = 0.0;
  return {first, last};
}

// The file's attributes, ancillary_data/ (the epoch, the data's first and last times) and
// orbit_info/ (the spacecraft's orientation; the orbit's numbers, which a simulation has not,
// their fill value).
void Granule::ancillary(const GranuleInfo& info, const std::string& short_name,
                        const std::vector<BeamTrack>& beams) {
  text_attribute(file(), "short_name", short_name);
  text_attribute(file(), "identifier_product_type", short_name);
  text_attribute(file(), "title", "glaswave simulation of ICESat-2 " + short_name);
  text_attribute(file(), "source", std::string("glaswave ") + GLASWAVE_VERSION);
  text_attribute(file(), "history", info.history);
  text_attribute(file(), "glaswave_config", info.config_json);
  const auto [first_s, last_s] = time_span(beams);
  const auto utc = [](double delta_time_s) {
    return format_iso8601_utc_microseconds(delta_time_s + atlas_epoch_since_glas_epoch_s);
  };
  const Group a = group(file(), "ancillary_data");
  dataset(
      a.get(), "atlas_sdp_gps_epoch", std::vector<double>{atlas_sdp_gps_epoch_s},
      {"seconds since 1980-01-06T00:00:00.000000Z", "ATLAS Epoch Offset", "auxiliaryInformation",
       "GPS seconds between the GPS epoch and the ATLAS Standard Data Product epoch "
       "(2018-01-01T00:00:00Z); add it to delta_time for GPS seconds"});
  text_dataset(a.get(), "data_start_utc", utc(first_s),
               {"1", "Start UTC Time of Granule (CCSDS-A, Actual)", "auxiliaryInformation",
                "UTC of the first shot"});
  text_dataset(a.get(), "data_end_utc", utc(last_s),
               {"1", "End UTC Time of Granule (CCSDS-A, Actual)", "auxiliaryInformation",
                "UTC of the last shot"});
  const Group o = group(file(), "orbit_info");
  dataset(o.get(), "sc_orient", std::vector<std::int8_t>{info.sc_orient},
          {"1", "Spacecraft Orientation", "modelResult",
           "0 backward (the left beam of each pair strong), 1 forward (the right beam strong), "
           "2 transition: the run's sensor.sc_orient (footprints/atlas_beams)"});
  dataset(o.get(), "sc_orient_time", std::vector<double>{first_s},
          {"seconds since 2018-01-01", "Time of Last Spacecraft Orientation Change",
           "referenceInformation", "The run's first shot: one orientation throughout"});
  dataset(o.get(), "rgt", std::vector<std::int16_t>{std::numeric_limits<std::int16_t>::max()},
          {"1", "Reference Ground track", "referenceInformation", "Not simulated: the fill value"},
          0, true);
  dataset(o.get(), "cycle_number",
          std::vector<std::int8_t>{std::numeric_limits<std::int8_t>::max()},
          {"1", "Cycle Number", "referenceInformation", "Not simulated: the fill value"}, 0, true);
}

std::int32_t segment_of(double along_m) {
  return static_cast<std::int32_t>(std::floor(along_m / segment_20m)) + 1;
}

// The 20 m segments a beam spans: from the first shot's to the last shot's.
struct Segments {
  std::int32_t first = 1;
  std::vector<std::int64_t> ph_index_beg;
  std::vector<std::int32_t> ph_cnt;
  std::vector<std::size_t> first_shot;  // the first shot in each segment (or its nearest before)
};

Segments segments_of(const BeamTrack& beam) {
  Segments s;
  if (beam.shots.empty()) return s;
  s.first = segment_of(beam.shots.front().along_m);
  const std::size_t count =
      static_cast<std::size_t>(segment_of(beam.shots.back().along_m) - s.first + 1);
  s.ph_index_beg.assign(count, 0);
  s.ph_cnt.assign(count, 0);
  s.first_shot.assign(count, beam.shots.size());
  for (std::size_t k = 0; k < beam.shots.size(); ++k) {
    const BeamShot& shot = beam.shots[k];
    const std::size_t j = static_cast<std::size_t>(segment_of(shot.along_m) - s.first);
    if (s.first_shot[j] == beam.shots.size()) s.first_shot[j] = k;
    if (shot.photon_count == 0) continue;
    if (s.ph_cnt[j] == 0) s.ph_index_beg[j] = static_cast<std::int64_t>(shot.first_photon) + 1;
    s.ph_cnt[j] += static_cast<std::int32_t>(shot.photon_count);
  }
  for (std::size_t j = 1; j < count; ++j)
    if (s.first_shot[j] == beam.shots.size()) s.first_shot[j] = s.first_shot[j - 1];
  return s;
}

// The `coordinates` attribute the data dictionaries give datasets (the datasets a reader pairs
// each with).
void add_coordinates(Granule& g, const std::string& parent,
                     std::initializer_list<const char*> names, const std::string& coordinates) {
  for (const char* name : names) g.text_attribute(parent + "/" + name, "coordinates", coordinates);
}

template <typename T>
constexpr T fill_of() {
  return std::numeric_limits<T>::max();
}

// orbit_info/orbit_number: one element, the fill value 65535: a simulation has no orbit count.
void write_orbit_number(Granule& g, const std::string& orbit_info) {
  g.dataset(orbit_info, "orbit_number", std::vector<std::uint16_t>{fill_of<std::uint16_t>()},
            {"1", "Orbit Number", "referenceInformation", "Not simulated: the fill value"}, 0,
            true);
}

// A beam group's attributes, as real granules give them: its strength, ATLAS's spot behind it,
// its name and the spacecraft's orientation.
void write_beam_attributes(Granule& g, const std::string& beam_group, const BeamTrack& beam,
                           std::int8_t sc_orient) {
  g.text_attribute(beam_group, "atlas_beam_type", beam.strong ? "strong" : "weak");
  g.text_attribute(beam_group, "atlas_spot_number", std::to_string(beam.spot_number));
  g.text_attribute(beam_group, "groundtrack_id", beam.name);
  g.text_attribute(beam_group, "sc_orientation",
                   sc_orient == atlas_sc_orient_forward ? "Forward" : "Backward");
}

// orbit_info/bounding_polygon_{lat1, lon1}: the granule's photons' latitude-longitude box (the
// shots' without photons), closed, counter-clockwise from its south-west corner; the fill value
// (one element) with neither.
void write_bounding_polygon(Granule& g, const std::string& orbit_info,
                            const std::vector<BeamTrack>& beams) {
  double south = 90.0, north = -90.0, west = 180.0, east = -180.0;
  const auto widen = [&](double lat, double lon) {
    south = std::min(south, lat), north = std::max(north, lat);
    west = std::min(west, lon), east = std::max(east, lon);
  };
  for (const BeamTrack& beam : beams) {
    for (const BeamPhoton& p : beam.photons) widen(p.lat_deg, p.lon_deg);
    if (beam.photons.empty())
      for (const BeamShot& s : beam.shots) widen(s.lat_deg, s.lon_deg);
  }
  std::vector<double> lat{fill_of<double>()}, lon{fill_of<double>()};
  if (south <= north) {
    lat = {south, south, north, north, south};
    lon = {west, east, east, west, west};
  }
  g.dataset(orbit_info, "bounding_polygon_lat1", lat,
            {"degrees_north", "Bounding Polygon Latitude", "referenceInformation",
             "The granule's photons' latitude-longitude box, closed, counter-clockwise from its "
             "south-west corner"},
            0, true);
  g.dataset(orbit_info, "bounding_polygon_lon1", lon,
            {"degrees_east", "Bounding Polygon Longitude", "referenceInformation",
             "The granule's photons' latitude-longitude box, closed, counter-clockwise from its "
             "south-west corner"},
            0, true);
}

// What the granules' ancillary_data/ and orbit_info/ hold beside Granule::ancillary's, as
// read-ICESat-2's read_granule reads them (each a one-element array): the GPS week and seconds
// of week of the first and last shots, the first and last 20 m segments, the granule's UTC span
// (the data's); the cycle, reference ground track, orbit and region, which a simulation has
// not, as the fill value; orbit_info/{orbit_number, crossing_time, lan}, fill likewise.
void write_ancillary_rest(Granule& g, const std::vector<BeamTrack>& beams) {
  const auto [first_s, last_s] = time_span(beams);
  std::int32_t first_segment = fill_of<std::int32_t>(), last_segment = fill_of<std::int32_t>();
  for (const BeamTrack& beam : beams) {
    if (beam.shots.empty()) continue;
    const std::int32_t a = segment_of(beam.shots.front().along_m);
    const std::int32_t b = segment_of(beam.shots.back().along_m);
    first_segment = first_segment == fill_of<std::int32_t>() ? a : std::min(first_segment, a);
    last_segment = last_segment == fill_of<std::int32_t>() ? b : std::max(last_segment, b);
  }
  const Group a("/ancillary_data");
  const std::string& h = a.get();
  const auto utc = [](double delta_time_s) {
    return format_iso8601_utc_microseconds(delta_time_s + atlas_epoch_since_glas_epoch_s);
  };
  constexpr double week_s = 604800.0;
  for (const auto& [which, t] : {std::pair<std::string, double>{"start", first_s},
                                 std::pair<std::string, double>{"end", last_s}}) {
    const std::string shot = which == "start" ? "first" : "last";
    const double gps_s = atlas_sdp_gps_epoch_s + t;
    const double week = std::floor(gps_s / week_s);
    const auto fill = [&](const std::string& name, const std::string& long_name) {
      g.dataset(h, which + "_" + name, std::vector<std::int32_t>{fill_of<std::int32_t>()},
                {"1", long_name, "auxiliaryInformation", "Not simulated: the fill value"}, 0, true);
    };
    fill("cycle", (which == "start" ? "Starting" : "Ending") + std::string(" Cycle"));
    g.dataset(
        h, which + "_geoseg",
        std::vector<std::int32_t>{which == "start" ? first_segment : last_segment},
        {"1", (which == "start" ? "Starting" : "Ending") + std::string(" Geolocation Segment"),
         "auxiliaryInformation",
         "The " + shot + " 20 m segment of the beams (geolocation/segment_id)"},
        0, true);
    g.dataset(h, which + "_gpssow", std::vector<double>{gps_s - week * week_s},
              {"seconds", (which == "start" ? "Start" : "End") + std::string(" GPS SOW of Granule"),
               "auxiliaryInformation", "GPS seconds of week of the " + shot + " shot"});
    g.dataset(h, which + "_gpsweek", std::vector<std::int32_t>{static_cast<std::int32_t>(week)},
              {"weeks from 1980-01-06",
               (which == "start" ? "Start" : "End") + std::string(" GPSWeek of Granule"),
               "auxiliaryInformation", "GPS week of the " + shot + " shot"});
    fill("orbit", (which == "start" ? "Starting" : "Ending") + std::string(" Orbit Number"));
    fill("region", (which == "start" ? "Starting" : "Ending") + std::string(" Region"));
    fill("rgt", (which == "start" ? "Starting" : "Ending") + std::string(" Reference Groundtrack"));
  }
  g.text_dataset(h, "granule_start_utc", utc(first_s),
                 {"1", "Start UTC Time of Granule (CCSDS-A, Requested)", "auxiliaryInformation",
                  "UTC of the first shot: the granule is the run's shots"});
  g.text_dataset(h, "granule_end_utc", utc(last_s),
                 {"1", "End UTC Time of Granule (CCSDS-A, Requested)", "auxiliaryInformation",
                  "UTC of the last shot: the granule is the run's shots"});
  g.text_dataset(h, "release", std::string("glaswave ") + GLASWAVE_VERSION,
                 {"1", "Release Number", "auxiliaryInformation",
                  "The glaswave version that simulated the granule (no ASAS release)"});
  g.text_dataset(h, "version", "01",
                 {"1", "Version", "auxiliaryInformation",
                  "01: the first (and only) production of these photons"});
  const Group o("/orbit_info");
  write_orbit_number(g, o.get());
  g.dataset(o.get(), "crossing_time", std::vector<double>{fill_of<double>()},
            {"seconds since 2018-01-01", "Ascending Node Crossing Time", "referenceInformation",
             "Not simulated: the fill value"},
            0, true);
  g.dataset(o.get(), "lan", std::vector<double>{fill_of<double>()},
            {"degrees_east", "Ascending Node Longitude", "referenceInformation",
             "Not simulated: the fill value"},
            0, true);
  write_bounding_polygon(g, o.get(), beams);
}

// ATL03's calibrations and impulse response, as read-ICESat-2's read_granule reads them:
// ancillary_data/calibrations/dead_time/gtXY/{dead_time (the beam's detector channels, 16 strong,
// 4 weak, each the sensor's dead time), sigma (0: one value, known)};
// calibrations/first_photon_bias/gtXY/{dead_time, strength, width, ffb_corr}, fill (no
// first-photon bias table is computed); ancillary_data/tep/{tep_range_prim, tep_valid_spot} and
// atlas_impulse_response/pce1_spot1, pce2_spot3/tep_histogram/{tep_hist, tep_hist_time,
// tep_hist_sum, tep_tod, tep_duration, tep_bckgrd}: the sensor's transmitted pulse, the same
// for both.
void write_atl03_calibrations(Granule& g, const GranuleInfo& info,
                              const std::vector<BeamTrack>& beams) {
  const Group a("/ancillary_data");
  const Group calibrations = g.group(a.get(), "calibrations");
  const Group dead_time = g.group(calibrations.get(), "dead_time");
  const Group bias = g.group(calibrations.get(), "first_photon_bias");
  const bool known = std::isfinite(info.dead_time_ns);
  for (const BeamTrack& beam : beams) {
    const Group d = g.group(dead_time.get(), beam.name);
    const std::size_t channels = beam.strong ? 16 : 4;
    g.dataset(d.get(), "dead_time",
              std::vector<double>(channels, known ? info.dead_time_ns * 1e-9 : fill_of<double>()),
              {"seconds", "Dead-time", "auxiliaryInformation",
               known ? "Each detector channel's non-paralysable dead time: the sensor's "
                       "(sensor.dead_time_ns), the same for every channel"
                     : "Not known: the fill value"},
              0, true);
    g.dataset(d.get(), "sigma", std::vector<double>(channels, known ? 0.0 : fill_of<double>()),
              {"seconds", "Dead-time sigma", "auxiliaryInformation",
               "0: the simulated dead time is exact"},
              0, true);
    const Group f = g.group(bias.get(), beam.name);
    const Meta none{"1", "First photon bias table", "auxiliaryInformation",
                    "Not computed (no first-photon bias calibration is simulated): the fill value"};
    for (const char* name : {"dead_time", "strength", "width", "ffb_corr"})
      g.dataset(f.get(), name, std::vector<double>{fill_of<double>()}, none, 0, true);
  }
  // The transmitted pulse as a histogram from its first sample: ATLAS's transmitter echo path.
  std::vector<double> time_s, hist;
  double sum = 0.0;
  for (const double p : info.pulse_power) sum += p;
  for (std::size_t i = 0; i < info.pulse_time_ns.size() && i < info.pulse_power.size(); ++i) {
    time_s.push_back((info.pulse_time_ns[i] - info.pulse_time_ns.front()) * 1e-9);
    hist.push_back(sum > 0.0 ? info.pulse_power[i] / sum : 0.0);
  }
  const double span_s = time_s.empty() ? 0.0 : time_s.back();
  const Group tep = g.group(a.get(), "tep");
  g.dataset(tep.get(), "tep_range_prim", std::vector<double>{0.0, span_s},
            {"seconds", "TEP primary range", "auxiliaryInformation",
             "The times of tep_hist_time that hold the primary TEP: the whole simulated pulse"});
  g.dataset(tep.get(), "tep_valid_spot", std::vector<std::int8_t>{1, 1, 2, 2, 1, 1},
            {"1", "Valid TEP spot", "auxiliaryInformation",
             "For spots 1-6, the TEP to use (1 pce1_spot1, 2 pce2_spot3); both are the sensor's "
             "pulse here"});
  const Group response = g.group(g.file(), "atlas_impulse_response");
  const auto [first_s, last_s] = time_span(beams);
  for (const char* pce : {"pce1_spot1", "pce2_spot3"}) {
    const Group p = g.group(response.get(), pce);
    const Group t = g.group(p.get(), "tep_histogram");
    g.dataset(t.get(), "tep_hist", hist,
              {"1", "TEP Histogram", "modelResult",
               "The sensor's transmitted pulse, its power in each sample over their sum (empty "
               "when the run has none)"});
    g.dataset(t.get(), "tep_hist_time", time_s,
              {"seconds", "TEP Histogram Time", "modelResult",
               "Each sample's time from the pulse's first sample"});
    g.dataset(t.get(), "tep_hist_sum", std::vector<std::int64_t>{fill_of<std::int64_t>()},
              {"counts", "TEP Histogram Sum", "modelResult",
               "Not counted (the pulse is known, not measured): the fill value"},
              0, true);
    g.dataset(t.get(), "tep_tod", std::vector<double>{first_s},
              {"seconds since 2018-01-01", "TEP Time Of Day", "referenceInformation",
               "The run's first shot: one pulse shape throughout"});
    g.dataset(t.get(), "tep_duration", std::vector<double>{last_s - first_s},
              {"seconds", "TEP Duration", "modelResult", "The run's span of shots"});
    g.dataset(t.get(), "tep_bckgrd", std::vector<double>{0.0},
              {"counts", "TEP Background", "modelResult", "0: the pulse is known without noise"});
  }
}

// Each photon's shot, in the photons' order.
std::vector<std::size_t> shot_of_photons(const BeamTrack& beam) {
  std::vector<std::size_t> shot(beam.photons.size(), 0);
  for (std::size_t k = 0; k < beam.shots.size(); ++k)
    for (std::uint32_t i = 0; i < beam.shots[k].photon_count; ++i)
      shot[beam.shots[k].first_photon + i] = k;
  return shot;
}

// The photons as the classification sees them. A shot's background rate becomes a density per
// m along track and m of height: rate * 2 / c photons a metre of height a shot, over the mean
// spacing of the shots.
std::vector<CloudPhoton> cloud_of(const BeamTrack& beam) {
  const std::vector<std::size_t> shot = shot_of_photons(beam);
  const double spacing_m = beam.shots.size() > 1
                               ? (beam.shots.back().along_m - beam.shots.front().along_m) /
                                     static_cast<double>(beam.shots.size() - 1)
                               : 1.0;
  std::vector<CloudPhoton> cloud(beam.photons.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const BeamShot& s = beam.shots[shot[i]];
    cloud[i] = {s.along_m, beam.photons[i].h_m,
                s.background_rate_Hz * 2.0 / 299792458.0 / std::max(spacing_m, 1e-3)};
  }
  return cloud;
}

template <typename T, typename F>
std::vector<T> each_photon(const BeamTrack& beam, F f) {
  std::vector<T> out;
  out.reserve(beam.photons.size());
  for (const BeamPhoton& p : beam.photons) out.push_back(static_cast<T>(f(p)));
  return out;
}

// Each photon's distance across track, right of the reference ground track: its beam's offset
// plus its own from its shot's footprint centre, across the direction from the shot before to
// the shot after (in the local east-north plane).
std::vector<float> across_track(const BeamTrack& beam, const std::vector<std::size_t>& shot) {
  constexpr double radius_m = 6371008.8, to_rad = std::numbers::pi / 180.0;
  std::vector<float> across(beam.photons.size());
  for (std::size_t i = 0; i < across.size(); ++i) {
    const std::size_t k = shot[i];
    const BeamShot& before = beam.shots[k > 0 ? k - 1 : k];
    const BeamShot& after = beam.shots[std::min(k + 1, beam.shots.size() - 1)];
    const double cos_lat = std::cos(beam.shots[k].lat_deg * to_rad);
    const double east = (after.lon_deg - before.lon_deg) * cos_lat;
    const double north = after.lat_deg - before.lat_deg;
    const double length = std::hypot(east, north);
    double offset_m = 0.0;
    if (length > 0.0) {
      const double d_east = (beam.photons[i].lon_deg - beam.shots[k].lon_deg) * cos_lat;
      const double d_north = beam.photons[i].lat_deg - beam.shots[k].lat_deg;
      offset_m = (d_east * north - d_north * east) / length * to_rad * radius_m;
    }
    across[i] = static_cast<float>(beam.across_m + offset_m);
  }
  return across;
}

void write_heights(Granule& g, const std::string& beam_group, const BeamTrack& beam,
                   const Atl08Classes& c) {
  const Group heights = g.group(beam_group, "heights");
  const std::string& h = heights.get();
  g.dataset(h, "h_ph", each_photon<float>(beam, [](auto& p) { return p.h_m; }),
            {"meters", "Photon WGS84 Height", "physicalMeasurement",
             "Height above the WGS84 ellipsoid of the point that scattered the photon (the "
             "simulation's exact one; a background photon's: the range it was timed at)"});
  g.dataset(h, "lat_ph", each_photon<double>(beam, [](auto& p) { return p.lat_deg; }),
            {"degrees_north", "Latitude", "modelResult", "Latitude of the photon's point"});
  g.dataset(h, "lon_ph", each_photon<double>(beam, [](auto& p) { return p.lon_deg; }),
            {"degrees_east", "Longitude", "modelResult", "Longitude of the photon's point"});
  g.dataset(h, "delta_time", each_photon<double>(beam, [](auto& p) { return p.delta_time_s; }),
            {delta_time_meta.units, delta_time_meta.long_name, delta_time_meta.content_type,
             "The transmit time of the photon's pulse; " + delta_time_meta.description});
  const std::vector<std::size_t> shot = shot_of_photons(beam);
  std::vector<float> along(beam.photons.size());
  for (std::size_t i = 0; i < along.size(); ++i) {
    const double x = beam.shots[shot[i]].along_m;
    along[i] = static_cast<float>(x - (segment_of(x) - 1) * segment_20m);
  }
  g.dataset(h, "dist_ph_along", along,
            {"meters", "Distance from Segment start", "modelResult",
             "Along-track distance of the photon's shot from the start of its 20 m segment"});
  g.dataset(h, "dist_ph_across", across_track(beam, shot),
            {"meters", "Distance off RGT", "modelResult",
             "Across-track distance of the photon's point right of the reference ground track: "
             "the beam's offset (footprints/atlas_beams) plus the point's from its shot's centre"});
  g.dataset(h, "quality_ph", std::vector<std::int8_t>(beam.photons.size(), 0),
            {"1", "Photon Quality", "qualityInformation",
             "0 nominal: the simulation has no afterpulses, impulse-response effects or TEP"});
  std::vector<std::int8_t> confidence(beam.photons.size() * 5, -1);
  for (std::size_t i = 0; i < beam.photons.size(); ++i) confidence[5 * i] = c.confidence[i];
  g.dataset(h, "signal_conf_ph", confidence,
            {"1", "Photon Signal Confidence", "modelResult",
             "Per surface type (land, ocean, sea ice, land ice, inland water): -1 not considered, "
             "0 noise, 2 low, 3 medium, 4 high; the land column from the classification's noise "
             "filter (pipeline/products/atl08_classification.hpp)"},
            5);
  g.dataset(h, "glaswave_truth_class",
            each_photon<std::uint8_t>(beam, [](auto& p) { return p.truth_class; }),
            truth_meta("1", "Simulation truth: 0 background, 1 ground, 2 canopy, 3 top of canopy"));
  g.dataset(h, "glaswave_order", each_photon<std::uint8_t>(beam, [](auto& p) { return p.order; }),
            truth_meta("1", "Simulation truth: scattering order, 0 for background"));
  // As the ATL03 data dictionary pairs them: every photon's field with its time and place.
  add_coordinates(g, h,
                  {"h_ph", "dist_ph_along", "dist_ph_across", "quality_ph", "signal_conf_ph",
                   "glaswave_truth_class", "glaswave_order"},
                  "delta_time lat_ph lon_ph");
  add_coordinates(g, h, {"lat_ph"}, "delta_time lon_ph");
  add_coordinates(g, h, {"lon_ph"}, "delta_time lat_ph");
  add_coordinates(g, h, {"delta_time"}, "lat_ph lon_ph");
}

// A 20 m segment's reference shot: its first (or the nearest before, for an empty one).
struct SegmentColumns {
  std::vector<std::int32_t> id;
  std::vector<double> dist, lat, lon, time;
  std::vector<float> solar_elevation, dem_h;
};

SegmentColumns segment_columns(const BeamTrack& beam, const Segments& s) {
  SegmentColumns c;
  for (std::size_t j = 0; j < s.ph_cnt.size(); ++j) {
    c.id.push_back(s.first + static_cast<std::int32_t>(j));
    c.dist.push_back((c.id.back() - 1) * segment_20m);
    const BeamShot& shot = beam.shots[s.first_shot[j]];
    c.lat.push_back(shot.lat_deg);
    c.lon.push_back(shot.lon_deg);
    c.time.push_back(shot.delta_time_s);
    c.solar_elevation.push_back(std::isfinite(shot.solar_elevation_deg)
                                    ? static_cast<float>(shot.solar_elevation_deg)
                                    : fill_float);
    c.dem_h.push_back(static_cast<float>(shot.ground_h_m));
  }
  return c;
}

void write_geolocation(Granule& g, const std::string& beam_group, const BeamTrack& beam) {
  const Segments s = segments_of(beam);
  const SegmentColumns c = segment_columns(beam, s);
  const Group geolocation = g.group(beam_group, "geolocation");
  const std::string& h = geolocation.get();
  g.dataset(h, "segment_id", c.id,
            {"1", "Along-track segment ID number", "referenceInformation",
             "20 m segments counted from 1 at the track's first shot"});
  g.dataset_filled(
      h, "ph_index_beg", s.ph_index_beg,
      {"counts", "Photon Index Begin", "referenceInformation",
       "1-based index in heights/ of the segment's first photon (0: none, the fill value)"},
      std::int64_t{0});
  g.dataset(h, "segment_ph_cnt", s.ph_cnt,
            {"counts", "Number of photons in a given along-track segment", "referenceInformation",
             "The segment's photons, consecutive in heights/"},
            0, true);
  std::vector<std::int32_t> reference(s.ph_cnt.size());
  for (std::size_t j = 0; j < reference.size(); ++j) reference[j] = s.ph_cnt[j] > 0 ? 1 : 0;
  g.dataset(h, "reference_photon_index", reference,
            {"counts", "Reference Photon Index", "referenceInformation",
             "1-based index of the segment's reference photon among its photons: 1, its first "
             "(0: the segment has none)"},
            0, true);
  g.dataset(h, "segment_dist_x", c.dist,
            {"meters", "Along-track distance", "modelResult",
             "Along-track distance of the segment's start from the track's first shot"});
  g.dataset(h, "segment_length", std::vector<double>(c.id.size(), segment_20m),
            {"meters", "Along-track length of segment", "modelResult", "20 m"});
  g.dataset(h, "reference_photon_lat", c.lat,
            {"degrees_north", "Latitude", "modelResult", "Latitude of the segment's first shot"});
  g.dataset(h, "reference_photon_lon", c.lon,
            {"degrees_east", "Longitude", "modelResult", "Longitude of the segment's first shot"});
  g.dataset(h, "delta_time", c.time,
            {delta_time_meta.units, delta_time_meta.long_name, delta_time_meta.content_type,
             "Time of the segment's first shot; " + delta_time_meta.description});
  g.dataset(h, "solar_elevation", c.solar_elevation,
            {"degrees", "solar elevation", "modelResult",
             "The sun's elevation above the first shot's footprint (footprints/solar_position)"},
            0, true);
  g.dataset(h, "sigma_h", std::vector<float>(c.id.size(), 0.0f),
            {"meters", "height uncertainty", "qualityInformation",
             "0: the simulation's photons are placed without geolocation error"},
            0, true);
  // The platform's, the pulse's and the range's (atl03_platform_fields.hpp), at the same shots.
  std::vector<const BeamShot*> reference_shots;
  for (const std::size_t k : s.first_shot) reference_shots.push_back(&beam.shots[k]);
  for (const SegmentField& field : atl03_platform_fields(beam, reference_shots)) {
    std::visit(
        [&](const auto& values) {
          g.dataset(h, field.name, values,
                    {field.units, field.long_name, field.content_type, field.description}, 0, true);
        },
        field.values);
    add_coordinates(g, h, {field.name.c_str()},
                    "delta_time reference_photon_lat reference_photon_lon");
  }
  add_coordinates(g, h,
                  {"segment_id", "ph_index_beg", "segment_ph_cnt", "reference_photon_index",
                   "segment_dist_x", "segment_length", "solar_elevation", "sigma_h"},
                  "delta_time reference_photon_lat reference_photon_lon");
  add_coordinates(g, h, {"reference_photon_lat"}, "delta_time reference_photon_lon");
  add_coordinates(g, h, {"reference_photon_lon"}, "delta_time reference_photon_lat");
  add_coordinates(g, h, {"delta_time"}, "reference_photon_lat reference_photon_lon");
  const Group corrections = g.group(beam_group, "geophys_corr");
  g.dataset(corrections.get(), "dem_h", c.dem_h,
            {"meters", "DEM Height", "referenceInformation",
             "The scene's terrain height above WGS84 at the segment's first shot"},
            0, true);
  g.dataset(corrections.get(), "delta_time", c.time, delta_time_meta);
  add_coordinates(g, corrections.get(), {"dem_h"},
                  "delta_time ../geolocation/reference_photon_lat "
                  "../geolocation/reference_photon_lon");
  add_coordinates(g, corrections.get(), {"delta_time"},
                  "../geolocation/reference_photon_lat ../geolocation/reference_photon_lon");
}

void write_background(Granule& g, const std::string& beam_group, const BeamTrack& beam) {
  const Group background = g.group(beam_group, "bckgrd_atlas");
  std::vector<float> rate;
  std::vector<double> time;
  for (const BeamShot& shot : beam.shots) {
    rate.push_back(static_cast<float>(shot.background_rate_Hz));
    time.push_back(shot.delta_time_s);
  }
  g.dataset(background.get(), "bckgrd_rate", rate,
            {"counts / second", "Background count rate", "modelResult",
             "Each shot's, estimated from its photons low in the range window over the 1001 "
             "shots about it (ATLAS's is per 50 shots)"});
  g.dataset(background.get(), "delta_time", time, delta_time_meta);
}

}  // namespace

std::vector<Atl08Classes> classify_beams(const std::vector<BeamTrack>& beams,
                                         const Atl08Settings& settings) {
  std::vector<Atl08Classes> out;
  for (const BeamTrack& beam : beams) out.push_back(classify_photons(cloud_of(beam), settings));
  return out;
}

void write_atl03(const std::filesystem::path& path, const std::vector<BeamTrack>& beams,
                 const std::vector<Atl08Classes>& classes, const GranuleInfo& info) {
  const std::lock_guard<std::mutex> hdf5(netcdf_library_mutex());  // HDF5 is not thread-safe
  Granule g(path);
  g.ancillary(info, "ATL03", beams);
  write_ancillary_rest(g, beams);
  write_atl03_calibrations(g, info, beams);
  for (std::size_t b = 0; b < beams.size(); ++b) {
    const Group beam_group = g.group(g.file(), beams[b].name);
    write_beam_attributes(g, beam_group.get(), beams[b], info.sc_orient);
    write_heights(g, beam_group.get(), beams[b], classes[b]);
    write_geolocation(g, beam_group.get(), beams[b]);
    write_background(g, beam_group.get(), beams[b]);
  }
  g.finish();
}

namespace {

struct SegmentTruth {
  std::vector<float> h_te, h_canopy, cover, pai, lat, lon, dem_h, solar_elevation;
  std::vector<float> lat_20m, lon_20m;  // segments x 5: the shot nearest each 20 m's centre
  std::vector<double> time;
  std::vector<std::int32_t> id_beg, id_end;
  std::vector<std::int32_t> night;  // ATL08's night_flag is int32
};

// The simulation's place and truth at one segment: `middle` its shot nearest the centre (null
// when it has none), `n` its shots and the sums of their truths.
void add_segment_truth(SegmentTruth& t, const BeamShot* middle, double n, double h, double ch,
                       double cv, double pai) {
  const auto mean = [&](double sum) { return n > 0.0 ? static_cast<float>(sum / n) : fill_float; };
  t.h_te.push_back(mean(h));
  t.h_canopy.push_back(mean(ch));
  t.cover.push_back(mean(cv));
  t.pai.push_back(mean(pai));
  t.lat.push_back(middle ? static_cast<float>(middle->lat_deg) : fill_float);
  t.lon.push_back(middle ? static_cast<float>(middle->lon_deg) : fill_float);
  t.time.push_back(middle ? middle->delta_time_s : fill_float);
  t.dem_h.push_back(middle ? static_cast<float>(middle->ground_h_m) : fill_float);
  const bool sun = middle && std::isfinite(middle->solar_elevation_deg);
  t.solar_elevation.push_back(sun ? static_cast<float>(middle->solar_elevation_deg) : fill_float);
  // ATL08's night_flag: the sun below the horizon.
  t.night.push_back(sun ? static_cast<std::int32_t>(middle->solar_elevation_deg < 0.0)
                        : std::numeric_limits<std::int32_t>::max());
}

// For each of `pieces` pieces of `width_m` along track from first_m, its shot nearest its
// centre (beam.shots.size() where it has none; shots past the end belong to the last piece).
std::vector<std::size_t> nearest_to_centres(const BeamTrack& beam, double first_m,
                                            std::size_t pieces, double width_m) {
  std::vector<std::size_t> nearest(pieces, beam.shots.size());
  std::vector<double> best(pieces, 1e300);
  for (std::size_t k = 0; k < beam.shots.size(); ++k) {
    const double along = beam.shots[k].along_m;
    const std::size_t j = static_cast<std::size_t>(
        std::clamp(std::floor((along - first_m) / width_m), 0.0, double(pieces - 1)));
    const double off = std::abs(along - (first_m + (j + 0.5) * width_m));
    if (off < best[j]) best[j] = off, nearest[j] = k;
  }
  return nearest;
}

// The shots' positions and the simulation's truth averaged over each land segment.
SegmentTruth segment_truth(const BeamTrack& beam, double first_m, std::size_t count,
                           double segment_m) {
  SegmentTruth t;
  const std::int32_t last_id = segment_of(beam.shots.back().along_m);  // ATL03's last segment
  std::vector<double> n(count, 0.0), h(count, 0.0), ch(count, 0.0), cv(count, 0.0), pai(count, 0.0);
  for (const BeamShot& s : beam.shots) {
    const std::size_t j = static_cast<std::size_t>(
        std::clamp(std::floor((s.along_m - first_m) / segment_m), 0.0, double(count - 1)));
    n[j] += 1.0;
    h[j] += s.ground_h_m;
    ch[j] += s.canopy_height_m;
    cv[j] += s.canopy_cover;
    pai[j] += s.pai;
  }
  const std::vector<std::size_t> middle = nearest_to_centres(beam, first_m, count, segment_m);
  for (std::size_t j = 0; j < count; ++j) {
    add_segment_truth(t, n[j] > 0.0 ? &beam.shots[middle[j]] : nullptr, n[j], h[j], ch[j], cv[j],
                      pai[j]);
    const double start = first_m + static_cast<double>(j) * segment_m;
    t.id_beg.push_back(segment_of(start));
    // The last land segment ends at the ATL03 segment of the last shot: past it there is none
    // (its end was one past whenever the track stopped inside its last 20 m).
    t.id_end.push_back(std::min(segment_of(start + segment_m) - 1, last_id));
  }
  for (const std::size_t k : nearest_to_centres(beam, first_m, 5 * count, segment_m / 5.0)) {
    const bool any = k < beam.shots.size();
    t.lat_20m.push_back(any ? static_cast<float>(beam.shots[k].lat_deg) : fill_float);
    t.lon_20m.push_back(any ? static_cast<float>(beam.shots[k].lon_deg) : fill_float);
  }
  return t;
}

// A value as float32, NaN (not measured) as the products' fill value.
float or_fill(double v) { return std::isnan(v) ? fill_float : static_cast<float>(v); }

// A land segments' five sub-segments' values, segments x 5 (fill for NaN).
std::vector<float> as_float_20m(const std::vector<LandSegment>& s,
                                std::array<double, 5> LandSegment::*member) {
  std::vector<float> out;
  for (const LandSegment& x : s)
    for (const double v : x.*member) out.push_back(or_fill(v));
  return out;
}

// The 20 m sub-segments (ATL08 from version 5): their places and heights; the subset flags,
// which rate the photons' spread in each, are not assessed (fill).
void write_20m(Granule& g, const std::string& land, const std::string& terrain,
               const std::string& canopy, const std::vector<LandSegment>& s,
               const SegmentTruth& t) {
  g.dataset(land, "latitude_20m", t.lat_20m,
            {"degrees_north", "Latitude of 20m segment", "modelResult",
             "The shot nearest each 20 m sub-segment's centre"},
            5, true);
  g.dataset(land, "longitude_20m", t.lon_20m,
            {"degrees_east", "Longitude of 20m segment", "modelResult",
             "The shot nearest each 20 m sub-segment's centre"},
            5, true);
  g.dataset(terrain, "h_te_best_fit_20m", as_float_20m(s, &LandSegment::h_te_best_fit_20m),
            {"meters", "Terrain height at 20m", "modelResult",
             "The fitted ground at each 20 m sub-segment's centre, with 3 ground photons there"},
            5, true);
  g.dataset(canopy, "h_canopy_20m", as_float_20m(s, &LandSegment::h_canopy_20m),
            {"meters", "Relative canopy height at 20m", "modelResult",
             "98th percentile of each 20 m sub-segment's canopy and top-of-canopy photons' "
             "heights above the fitted ground, with 5 of them there"},
            5, true);
  const std::vector<std::int8_t> unassessed(5 * s.size(), std::numeric_limits<std::int8_t>::max());
  g.dataset(terrain, "subset_te_flag", unassessed,
            {"1", "Terrain subset flag", "qualityInformation", "Not assessed: the fill value"}, 5,
            true);
  g.dataset(canopy, "subset_can_flag", unassessed,
            {"1", "Canopy subset flag", "qualityInformation", "Not assessed: the fill value"}, 5,
            true);
}

std::vector<float> as_float(const std::vector<LandSegment>& s, double LandSegment::*member) {
  std::vector<float> out;
  for (const LandSegment& x : s) out.push_back(or_fill(x.*member));
  return out;
}

// A land segment's value written as float32, NaN as the fill value, one dataset a field in order.
struct SegmentField {
  const char* name;
  double LandSegment::*member;
  Meta meta;
};

void write_segment_fields(Granule& g, const std::string& h, const std::vector<LandSegment>& s,
                          const std::vector<SegmentField>& fields) {
  for (const SegmentField& f : fields) g.dataset(h, f.name, as_float(s, f.member), f.meta, 0, true);
}

std::vector<std::int32_t> as_int(const std::vector<LandSegment>& s,
                                 std::int32_t LandSegment::*member) {
  std::vector<std::int32_t> out;
  for (const LandSegment& x : s) out.push_back(x.*member);
  return out;
}

// land_segments/: where and when, the reference surface, the sun, the flags.
void write_segment_place(Granule& g, const std::string& h, const std::vector<LandSegment>& s,
                         const SegmentTruth& t) {
  g.dataset(h, "latitude", t.lat,
            {"degrees_north", "Latitude", "modelResult", "The shot nearest the segment's centre"},
            0, true);
  g.dataset(h, "longitude", t.lon,
            {"degrees_east", "Longitude", "modelResult", "The shot nearest the segment's centre"},
            0, true);
  g.dataset(h, "delta_time", t.time,
            {delta_time_meta.units, delta_time_meta.long_name, delta_time_meta.content_type,
             "The shot nearest the segment's centre; " + delta_time_meta.description});
  g.dataset(h, "segment_id_beg", t.id_beg,
            {"1", "Beginning Segment ID", "referenceInformation", "Its first ATL03 20 m segment"});
  g.dataset(h, "segment_id_end", t.id_end,
            {"1", "Ending Segment ID", "referenceInformation", "Its last ATL03 20 m segment"});
  g.dataset(h, "dem_h", t.dem_h,
            {"meters", "Reference DEM height", "modelResult",
             "The scene's terrain height above WGS84 at the shot nearest the centre"},
            0, true);
  g.dataset(h, "solar_elevation", t.solar_elevation,
            {"degrees", "Solar Angle Above or Below the Horizon", "modelResult",
             "The sun's elevation at the shot nearest the centre"},
            0, true);
  g.dataset(h, "night_flag", t.night,
            {"1", "Night Flag", "modelResult", "1 when the sun is below the horizon, else 0"}, 0,
            true);
  std::vector<float> snr;
  std::vector<std::int32_t> terrain_flg;
  for (const LandSegment& x : s) {
    const int signal = x.n_te_photons + x.n_ca_photons + x.n_toc_photons;
    snr.push_back(x.n_noise_photons > 0 ? static_cast<float>(signal) / x.n_noise_photons
                                        : fill_float);
    terrain_flg.push_back(std::isnan(x.h_te_best_fit) ? 1 : 0);
  }
  g.dataset(h, "snr", snr,
            {"1", "Signal to Noise Ratio", "qualityInformation",
             "The segment's signal photons (ground, canopy, top of canopy) over its noise "
             "photons, both from the classification"},
            0, true);
  g.dataset(h, "terrain_flg", terrain_flg,
            {"1", "Terrain Flag", "qualityInformation",
             "1 where the segment has no terrain height (too few ground photons), else 0"});
}

// ATL09's flags of the layers over a segment whose ground is `ground_h` above the ellipsoid (NaN:
// not known), as ATL08 defines them: msw_flag 0 without layers, else by the lowest layer's base
// above the ground, 3 below 1 km, 2 from 1 to 3 km, 1 above 3 km (4 and 5, blowing snow, never;
// -1 where the ground is not known); cloud_flag_atm the number of layers (0-10); layer_flag 1
// where there are any.
struct LayerFlags {
  std::vector<std::int8_t> msw, cloud_atm, layer;
};
LayerFlags layer_flags(const std::vector<CloudLayer>& layers, const std::vector<float>& ground_h) {
  LayerFlags f;
  for (const float h : ground_h) {
    double lowest_m = std::numeric_limits<double>::infinity();
    for (const CloudLayer& layer : layers)
      lowest_m = std::min(lowest_m, layer.base_m - (layer.above_ellipsoid ? h : 0.0));
    const bool known =
        h != fill_float || std::none_of(layers.begin(), layers.end(),
                                        [](const CloudLayer& l) { return l.above_ellipsoid; });
    f.msw.push_back(layers.empty()       ? 0
                    : !known             ? -1
                    : lowest_m < 1000.0  ? 3
                    : lowest_m <= 3000.0 ? 2
                                         : 1);
    f.cloud_atm.push_back(static_cast<std::int8_t>(std::min<std::size_t>(layers.size(), 10)));
    f.layer.push_back(layers.empty() ? 0 : 1);
  }
  return f;
}

// land_segments/ flags: the atmosphere's layers where the run has an `atmosphere` section (else
// none: no clouds or blowing snow); no photons removed between ATL03 and ATL08; saturation is
// not assessed (fill).
void write_segment_flags(Granule& g, const std::string& h, const std::vector<float>& ground_h,
                         const GranuleInfo& info) {
  const std::size_t count = ground_h.size();
  const std::vector<std::int8_t> zero(count, 0);
  if (info.cloud_layers) {
    const LayerFlags f = layer_flags(*info.cloud_layers, ground_h);
    const char* found =
        "from the simulated atmosphere's layers whose backscatter at least equals the molecules' "
        "(their base above the segment's dem_h)";
    g.dataset(h, "msw_flag", f.msw,
              {"1", "Multiple Scattering Warning Flag", "qualityInformation",
               std::string("0 no layers; the lowest layer's base below 1 km 3, 1-3 km 2, above 3 "
                           "km 1; no blowing snow (4, 5): ") +
                   found});
    g.dataset(h, "cloud_flag_atm", f.cloud_atm,
              {"1", "Cloud Flag from Atmosphere", "qualityInformation",
               std::string("Number of cloud or aerosol layers (0-10), ") + found});
    g.dataset(h, "layer_flag", f.layer,
              {"1", "Consolidated Cloud Flag", "qualityInformation",
               std::string("1 where there are cloud or aerosol layers, else 0: ") + found});
  } else {
    g.dataset(h, "msw_flag", zero,
              {"1", "Multiple Scattering Warning Flag", "qualityInformation",
               "0 (no layers): the simulated atmosphere has no clouds or blowing snow"});
    g.dataset(h, "layer_flag", zero,
              {"1", "Consolidated Cloud Flag", "qualityInformation",
               "0 (clear): the simulated atmosphere has no clouds or blowing snow"});
  }
  g.dataset(h, "segment_watermask", std::vector<std::int32_t>(count, 0),  // int32 as real ATL08
            {"1", "Water mask", "referenceInformation",
             "0 (no water): the simulated scenes have no inland water"},
            0, true);
  g.dataset(h, "ph_removal_flag", zero,
            {"1", "Photon Removal Flag", "qualityInformation",
             "0: no signal photons are removed between the classification's two steps"});
  g.dataset(h, "sat_flag", std::vector<std::int8_t>(count, std::numeric_limits<std::int8_t>::max()),
            {"1", "Saturation Flag", "qualityInformation", "Not assessed: the fill value"}, 0,
            true);
}

void write_terrain(Granule& g, const std::string& h, const std::vector<LandSegment>& s) {
  write_segment_fields(
      g, h, s,
      {
          {"h_te_best_fit",
           &LandSegment::h_te_best_fit,
           {"meters", "Best fit terrain elevation", "modelResult",
            "The classification's fitted ground at the segment's centre"}},
          {"h_te_mean",
           &LandSegment::h_te_mean,
           {"meters", "Mean terrain elevation", "modelResult",
            "Mean of the segment's ground photons' heights"}},
          {"h_te_median",
           &LandSegment::h_te_median,
           {"meters", "Median terrain elevation", "modelResult",
            "Median of the segment's ground photons' heights"}},
          {"h_te_uncertainty",
           &LandSegment::h_te_uncertainty,
           {"meters", "Uncertainty of the mean terrain height", "qualityInformation",
            "The ground photons' RMS about their least-squares line over sqrt(n_te_photons); "
            "no geolocation error is simulated"}},
          {"h_te_min",
           &LandSegment::h_te_min,
           {"meters", "Minimum terrain elevation", "modelResult",
            "Lowest of the segment's ground photons' heights"}},
          {"h_te_max",
           &LandSegment::h_te_max,
           {"meters", "Maximum terrain elevation", "modelResult",
            "Highest of the segment's ground photons' heights"}},
          {"terrain_slope",
           &LandSegment::terrain_slope,
           {"1", "Terrain slope", "modelResult",
            "Along-track slope of the least-squares line through the ground photons"}},
          {"h_te_std",
           &LandSegment::h_te_std,
           {"meters", "Standard deviation of terrain points", "modelResult",
            "Standard deviation (n - 1) of the segment's ground photons' heights"}},
      });
  write_segment_fields(g, h, s,
                       {{"h_te_mode",
                         &LandSegment::h_te_mode,
                         {"meters", "Mode of terrain height", "modelResult",
                          "Mode of the segment's ground photons' heights: the centre of the "
                          "fullest 0.1 m bin (bins centred on multiples of 0.1 m), the lowest "
                          "of ties"}}});
  g.dataset(h, "n_te_photons", as_int(s, &LandSegment::n_te_photons),
            {"1", "Number of ground photons", "modelResult", "The segment's ground photons"});
}

// canopy/'s distribution of the canopy photons' heights above the ground: its least, median and
// greatest, and canopy_h_metrics (segments x 18: the 10th, 15th, ..., 95th percentiles).
void write_canopy_distribution(Granule& g, const std::string& h, const std::vector<LandSegment>& s,
                               const std::string& above) {
  write_segment_fields(
      g, h, s,
      {
          {"h_min_canopy",
           &LandSegment::h_min_canopy,
           {"meters", "Minimum relative canopy height", "modelResult", "Least" + above}},
          {"h_median_canopy",
           &LandSegment::h_median_canopy,
           {"meters", "Median relative canopy height", "modelResult", "Median" + above}},
          {"h_max_canopy",
           &LandSegment::h_max_canopy,
           {"meters", "Maximum relative canopy height", "modelResult", "Greatest" + above}},
      });
  std::vector<float> metrics;
  for (const LandSegment& x : s)
    for (const double v : x.canopy_h_metrics) metrics.push_back(or_fill(v));
  g.dataset(h, "canopy_h_metrics", metrics,
            {"meters", "Relative canopy height metrics", "modelResult",
             "The 10th, 15th, ..., 95th percentiles" + above},
            18, true);
}

void write_canopy(Granule& g, const std::string& h, const std::vector<LandSegment>& s) {
  const std::string above =
      " of the canopy and top-of-canopy photons' heights above the fitted "
      "ground";
  write_segment_fields(
      g, h, s,
      {
          {"h_canopy",
           &LandSegment::h_canopy,
           {"meters", "Relative canopy height", "modelResult", "98th percentile" + above}},
          {"canopy_openness",
           &LandSegment::canopy_openness,
           {"meters", "Canopy openness", "modelResult", "Standard deviation" + above}},
          {"h_mean_canopy",
           &LandSegment::h_mean_canopy,
           {"meters", "Mean relative canopy height", "modelResult", "Mean" + above}},
          {"h_mean_canopy_abs",
           &LandSegment::h_mean_canopy_abs,
           {"meters", "Mean absolute canopy height", "modelResult",
            "Mean of the canopy and top-of-canopy photons' heights above WGS84"}},
      });
  write_canopy_distribution(g, h, s, above);
  g.dataset(h, "h_canopy_uncertainty", std::vector<float>(s.size(), fill_float),
            {"meters", "Uncertainty of the relative canopy height", "qualityInformation",
             "Not estimated: the fill value"},
            0, true);
  g.dataset(h, "n_ca_photons", as_int(s, &LandSegment::n_ca_photons),
            {"1", "Number of canopy photons", "modelResult", "The segment's canopy photons"});
  g.dataset(h, "n_toc_photons", as_int(s, &LandSegment::n_toc_photons),
            {"1", "Number of top of canopy photons", "modelResult",
             "The segment's top-of-canopy photons"});
  write_segment_fields(g, h, s,
                       {{"toc_roughness",
                         &LandSegment::toc_roughness,
                         {"meters", "Top of canopy roughness", "modelResult",
                          "Standard deviation (n - 1) of the top-of-canopy photons' heights above "
                          "the fitted ground"}}});
  std::vector<std::int8_t> confidence;
  for (const LandSegment& x : s)
    confidence.push_back(x.canopy_rh_conf < 0 ? fill_of<std::int8_t>() : x.canopy_rh_conf);
  g.dataset(h, "canopy_rh_conf", confidence,
            {"1", "Canopy relative height confidence", "qualityInformation",
             "From the shares of canopy (canopy and top of canopy) and ground photons among the "
             "segment's classified photons: 0 canopy < 5 %, 1 canopy >= 5 % and ground < 5 %, "
             "2 canopy >= 5 % and ground >= 5 %; the fill value without classified photons"},
            0, true);
}

// land_segments/{ph_ndx_beg, n_seg_ph}: each segment's first photon in signal_photons/ (1-based,
// as ATL08 writes it; the fill value without one) and its count there. signal_photons/ holds
// the classified photons in photon order, which is along-track order (write_signal_photons).
void write_segment_photons(Granule& g, const std::string& h, const BeamTrack& beam,
                           const Atl08Classes& classes, double first_m, double segment_m,
                           std::size_t count) {
  std::vector<std::int64_t> first(count, fill_of<std::int64_t>());
  std::vector<std::int32_t> n(count, 0);
  const std::vector<CloudPhoton> cloud = cloud_of(beam);
  std::int64_t signal = 0;  // classified photons before this one
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (classes.classes[i] == 0) continue;
    ++signal;
    const double k = std::floor((cloud[i].along_m - first_m) / segment_m);
    if (k < 0.0 || k >= static_cast<double>(count)) continue;
    const auto j = static_cast<std::size_t>(k);
    if (n[j]++ == 0) first[j] = signal;
  }
  g.dataset(h, "ph_ndx_beg", first,
            {"1", "Photon Index Begin", "referenceInformation",
             "1-based index in signal_photons/ of the segment's first classified photon"},
            0, true);
  g.dataset(h, "n_seg_ph", n,
            {"1", "Number of photons in segment", "referenceInformation",
             "The segment's classified photons in signal_photons/ (ground, canopy, top of "
             "canopy)"});
}

void write_segment_truth(Granule& g, const std::string& land, const SegmentTruth& t) {
  const Group truth = g.group(land, "glaswave_truth");
  const std::string& h = truth.get();
  g.dataset(h, "h_te", t.h_te,
            truth_meta("meters",
                       "Simulation truth: mean terrain height at the segment's footprint centres"),
            0, true);
  g.dataset(h, "h_canopy", t.h_canopy,
            truth_meta("meters", "Simulation truth: mean of the footprints' canopy heights"), 0,
            true);
  g.dataset(h, "canopy_cover", t.cover,
            truth_meta("1", "Simulation truth: mean of the footprints' crown cover"), 0, true);
  g.dataset(h, "pai", t.pai, truth_meta("1", "Simulation truth: mean of the footprints' PAI"), 0,
            true);
}

void write_land_segments(Granule& g, const std::string& beam_group, const BeamTrack& beam,
                         const Atl08Classes& classes, const Atl08Settings& settings,
                         const GranuleInfo& info) {
  if (beam.shots.empty()) return;
  const double first_m =
      std::floor(beam.shots.front().along_m / settings.segment_m) * settings.segment_m;
  const double end_m = beam.shots.back().along_m + 1e-9;
  const std::vector<LandSegment> s =
      land_segments(cloud_of(beam), classes, first_m, end_m, settings);
  const SegmentTruth t = segment_truth(beam, first_m, s.size(), settings.segment_m);
  const Group land = g.group(beam_group, "land_segments");
  write_segment_place(g, land.get(), s, t);
  write_segment_photons(g, land.get(), beam, classes, first_m, settings.segment_m, s.size());
  write_segment_flags(g, land.get(), t.dem_h, info);
  const Group terrain = g.group(land.get(), "terrain");
  const Group canopy = g.group(land.get(), "canopy");
  write_terrain(g, terrain.get(), s);
  write_canopy(g, canopy.get(), s);
  // ATL08 takes segment_cover from a reference map of canopy cover (as dem_h from a reference
  // DEM); the scene is this one's.
  std::vector<std::int16_t> cover;
  for (const float c : t.cover)
    cover.push_back(c == fill_float ? std::numeric_limits<std::int16_t>::max()
                                    : static_cast<std::int16_t>(std::lround(100.0 * c)));
  g.dataset(canopy.get(), "segment_cover", cover,
            {"percent", "Segment Cover", "referenceInformation",
             "The scene's crown cover over the segment's footprints (the mean of the "
             "simulation's), in percent, rounded"},
            0, true);
  write_20m(g, land.get(), terrain.get(), canopy.get(), s, t);
  write_segment_truth(g, land.get(), t);
}

void write_signal_photons(Granule& g, const std::string& beam_group, const BeamTrack& beam,
                          const Atl08Classes& classes) {
  const std::vector<std::size_t> shot = shot_of_photons(beam);
  std::vector<std::int8_t> flag;
  std::vector<std::int32_t> index, segment;
  std::vector<float> height;
  std::vector<double> time;
  std::int32_t current = 0, first_in_segment = 0;
  for (std::size_t i = 0; i < beam.photons.size(); ++i) {
    const std::int32_t id = segment_of(beam.shots[shot[i]].along_m);
    if (id != current) current = id, first_in_segment = static_cast<std::int32_t>(i);
    if (classes.classes[i] == 0) continue;
    flag.push_back(static_cast<std::int8_t>(classes.classes[i]));
    index.push_back(static_cast<std::int32_t>(i) - first_in_segment + 1);
    segment.push_back(id);
    height.push_back(
        static_cast<float>(beam.photons[i].h_m - classes.ground_at(beam.shots[shot[i]].along_m)));
    time.push_back(beam.photons[i].delta_time_s);
  }
  const Group signal = g.group(beam_group, "signal_photons");
  const std::string& h = signal.get();
  g.dataset(h, "classed_pc_flag", flag,
            {"1", "Photon Land Classification", "modelResult",
             "1 ground, 2 canopy, 3 top of canopy (the classification's; noise is left out)"});
  g.dataset(h, "classed_pc_indx", index,
            {"1", "Classified Photon Index", "referenceInformation",
             "1-based index of the photon among its ATL03 20 m segment's photons"});
  g.dataset(h, "ph_segment_id", segment,
            {"1", "Georeferenced Segment ID", "referenceInformation",
             "The photon's ATL03 20 m segment (geolocation/segment_id)"});
  g.dataset(h, "ph_h", height,
            {"meters", "Height of photon above interpolated ground surface", "modelResult",
             "The photon's height above the classification's fitted ground at its shot"});
  g.dataset(h, "d_flag", std::vector<std::int8_t>(flag.size(), 1),
            {"1", "DRAGANN flag", "qualityInformation",
             "1: every classified photon passed the noise filter (signal)"});
  g.dataset(h, "delta_time", time,
            {delta_time_meta.units, delta_time_meta.long_name, delta_time_meta.content_type,
             "The transmit time of the photon's pulse; " + delta_time_meta.description});
}

}  // namespace

void write_atl08(const std::filesystem::path& path, const std::vector<BeamTrack>& beams,
                 const std::vector<Atl08Classes>& classes, const Atl08Settings& settings,
                 const GranuleInfo& info) {
  const std::lock_guard<std::mutex> hdf5(netcdf_library_mutex());  // HDF5 is not thread-safe
  Granule g(path);
  g.ancillary(info, "ATL08", beams);
  write_ancillary_rest(g, beams);
  for (std::size_t b = 0; b < beams.size(); ++b) {
    const Group beam_group = g.group(g.file(), beams[b].name);
    write_beam_attributes(g, beam_group.get(), beams[b], info.sc_orient);
    write_land_segments(g, beam_group.get(), beams[b], classes[b], settings, info);
    write_signal_photons(g, beam_group.get(), beams[b], classes[b]);
  }
  g.finish();
}

}  // namespace glaswave
