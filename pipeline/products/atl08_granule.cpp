// The ATL08-like granule (PRODUCT.md section 9): per beam land_segments/ of 100 m from the
// photons' own classification, their 20 m sub-segments, signal_photons/ linking each classified
// photon back to ATL03, the simulation's truth beside them; written through the granules' shared
// layout (icesat2_layout.hpp).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "core/netcdf_lock.hpp"
#include "pipeline/products/icesat2_layout.hpp"
#include "pipeline/products/icesat2_products.hpp"

namespace glaswave {

using namespace icesat2;

namespace {

struct SegmentTruth {
  std::vector<float> h_te, h_canopy, cover, pai, pgap, lat, lon, dem_h, solar_elevation;
  std::vector<float> lat_20m, lon_20m;  // segments x 5: the shot nearest each 20 m's centre
  std::vector<double> time;
  std::vector<std::int32_t> id_beg, id_end;
  std::vector<std::int32_t> night;  // ATL08's night_flag is int32
};

// The simulation's place and truth at one segment: `middle` its shot nearest the centre (null
// when it has none), `n` its shots and the sums of their truths.
void add_segment_truth(SegmentTruth& t, const BeamShot* middle, double n, double h, double ch,
                       double cv, double pai, double pgap) {
  const auto mean = [&](double sum) { return n > 0.0 ? static_cast<float>(sum / n) : fill_float; };
  t.h_te.push_back(mean(h));
  t.h_canopy.push_back(mean(ch));
  t.cover.push_back(mean(cv));
  t.pai.push_back(mean(pai));
  t.pgap.push_back(mean(pgap));
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
  std::vector<double> n(count, 0.0), h(count, 0.0), ch(count, 0.0), cv(count, 0.0), pai(count, 0.0),
      pgap(count, 0.0);
  for (const BeamShot& s : beam.shots) {
    const std::size_t j = static_cast<std::size_t>(
        std::clamp(std::floor((s.along_m - first_m) / segment_m), 0.0, double(count - 1)));
    n[j] += 1.0;
    h[j] += s.ground_h_m;
    ch[j] += s.canopy_height_m;
    cv[j] += s.canopy_cover;
    pai[j] += s.pai;
    pgap[j] += s.pgap;
  }
  const std::vector<std::size_t> middle = nearest_to_centres(beam, first_m, count, segment_m);
  for (std::size_t j = 0; j < count; ++j) {
    add_segment_truth(t, n[j] > 0.0 ? &beam.shots[middle[j]] : nullptr, n[j], h[j], ch[j], cv[j],
                      pai[j], pgap[j]);
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
  g.dataset(h, "pgap", t.pgap,
            truth_meta("1", "Simulation truth: mean of the footprints' vertical gap probability"),
            0, true);
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
