// The ATL03-like granule (PRODUCT.md section 9): per beam heights/ per photon, geolocation/ 20 m
// segments with 1-based photon index ranges, bckgrd_atlas/, ATL03's calibrations; written through
// the granules' shared layout (icesat2_layout.hpp), with no object time stamps, so that the same
// photons give the same bytes.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <type_traits>
#include <utility>
#include <variant>

#include "core/error.hpp"
#include "core/netcdf_lock.hpp"
#include "pipeline/products/atl03_platform_fields.hpp"
#include "pipeline/products/icesat2_layout.hpp"
#include "pipeline/products/icesat2_products.hpp"

namespace glaswave {

using namespace icesat2;

namespace {

// The `coordinates` attribute the data dictionaries give datasets (the datasets a reader pairs
// each with).
void add_coordinates(Granule& g, const std::string& parent,
                     std::initializer_list<const char*> names, const std::string& coordinates) {
  for (const char* name : names) g.text_attribute(parent + "/" + name, "coordinates", coordinates);
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
    if (std::isfinite(beams[b].photons_per_J)) {
      const Group truth = g.group(beam_group.get(), "glaswave_truth");
      g.dataset(truth.get(), "photons_per_joule", std::vector<double>{beams[b].photons_per_J},
                truth_meta("1/J",
                           "Simulation truth: the photons this beam detects per joule of the "
                           "return of the band's whole (strong beam's) pulse, its share of the "
                           "pulse included: what rt on these photons scales its table by"));
    }
  }
  g.finish();
}
}  // namespace glaswave
