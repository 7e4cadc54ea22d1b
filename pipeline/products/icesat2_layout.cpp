// The ICESat-2 granules' shared layout (icesat2_layout.hpp): the file's attributes,
// ancillary_data/ and orbit_info/, the beams' groups, the 20 m segments, the photons' cloud.
#include "pipeline/products/icesat2_layout.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/glas_time.hpp"

namespace glaswave::icesat2 {
namespace {

// orbit_info/orbit_number: one element, the fill value 65535: a simulation has no orbit count.
void write_orbit_number(Granule& g, const std::string& orbit_info) {
  g.dataset(orbit_info, "orbit_number", std::vector<std::uint16_t>{fill_of<std::uint16_t>()},
            {"1", "Orbit Number", "referenceInformation", "Not simulated: the fill value"}, 0,
            true);
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

}  // namespace

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

Meta truth_meta(const std::string& units, const std::string& long_name) {
  return {units, long_name, "modelResult", "glaswave's own: the simulation's truth"};
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

void write_beam_attributes(Granule& g, const std::string& beam_group, const BeamTrack& beam,
                           std::int8_t sc_orient) {
  g.text_attribute(beam_group, "atlas_beam_type", beam.strong ? "strong" : "weak");
  g.text_attribute(beam_group, "atlas_spot_number", std::to_string(beam.spot_number));
  g.text_attribute(beam_group, "groundtrack_id", beam.name);
  g.text_attribute(beam_group, "sc_orientation",
                   sc_orient == atlas_sc_orient_forward ? "Forward" : "Backward");
}

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
    const std::string& end = which;  // clang 14 refuses a lambda naming a structured binding
    const double gps_s = atlas_sdp_gps_epoch_s + t;
    const double week = std::floor(gps_s / week_s);
    const auto fill = [&](const std::string& name, const std::string& long_name) {
      g.dataset(h, end + "_" + name, std::vector<std::int32_t>{fill_of<std::int32_t>()},
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

std::vector<std::size_t> shot_of_photons(const BeamTrack& beam) {
  std::vector<std::size_t> shot(beam.photons.size(), 0);
  for (std::size_t k = 0; k < beam.shots.size(); ++k)
    for (std::uint32_t i = 0; i < beam.shots[k].photon_count; ++i)
      shot[beam.shots[k].first_photon + i] = k;
  return shot;
}

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

}  // namespace glaswave::icesat2
