// `glaswave retrieve`: shots.nc read, the methods run on every shot in parallel, retrieval.nc
// written under the names PRODUCT.md section 11 gives.
#include "pipeline/retrieval/retrieve.hpp"

#include <netcdf.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <numbers>
#include <utility>

#include "core/error.hpp"
#include "pipeline/products/canopy_indices.hpp"
#include "pipeline/products/gedi_granule.hpp"
#include "pipeline/products/gedi_l2a_groups.hpp"
#include "pipeline/products/gedi_l2b_algorithm.hpp"
#include "pipeline/retrieval/gedi_l1b_reader.hpp"
#include "pipeline/retrieval/netcdf_file.hpp"
#include "pipeline/retrieval/retrieve_inputs.hpp"

namespace glaswave {

namespace {

using nlohmann::json;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The noise of a waveform with a detector: mean and sd of the quieter of its two ends (15 % of
// the bins each, as the products' waveform processing takes it).
std::pair<double, double> end_noise(const std::vector<double>& w) {
  const std::size_t n = std::max<std::size_t>(2, w.size() * 15 / 100);
  std::pair<double, double> best{kNaN, kNaN};
  for (int end = 0; end < 2; ++end) {
    double sum = 0.0, sum2 = 0.0;
    for (std::size_t i = 0; i < n && i < w.size(); ++i) {
      const double x = end == 0 ? w[i] : w[w.size() - 1 - i];
      sum += x;
      sum2 += x * x;
    }
    const double mean = sum / n;
    const double sd = std::sqrt(std::max(0.0, sum2 / n - mean * mean));
    if (std::isnan(best.first) || mean < best.first) best = {mean, sd};
  }
  return best;
}

bool detector_enabled(const json& config) {
  const auto d = config.find("detector");
  if (d == config.end() || !d->is_object()) return false;
  const auto e = d->find("enabled");
  return e != d->end() && e->is_boolean() && e->get<bool>();
}

double config_number(const json& config, const char* section, const char* key,
                     const std::string& file) {
  const auto s = config.find(section);
  if (s != config.end() && s->is_object()) {
    const auto k = s->find(key);
    if (k != s->end() && k->is_number()) return k->get<double>();
  }
  throw input_error(file, std::string("its `config` attribute has no ") + section + "." + key);
}

}  // namespace

MeasuredShots read_shots(const std::filesystem::path& file, std::optional<std::int64_t> first,
                         std::optional<std::int64_t> last) {
  const NetcdfFile nc = NetcdfFile::open(file);
  const std::string place = file.string();
  const std::optional<std::string> config_text = nc.text_attribute("", "config");
  if (!config_text || !nc.has_variable("rx_waveform"))
    throw input_error(
        place,
        "neither a glaswave shots.nc (no `config` attribute or `rx_waveform`) "
        "nor a GEDI L1B granule (no BEAMxxxx/rxwaveform) nor a GLAH01 or GLAH14 "
        "granule (no Data_40HZ/Waveform/RecWaveform/r_rng_wf or "
        "Elevation_Surfaces/d_elev) nor an ATL08 or ATL03 granule (no gtXY/land_segments or "
        "gtXY/heights/h_ph)");
  json config;
  try {
    config = json::parse(*config_text);
  } catch (const json::exception&) {
    throw input_error(place, "its `config` attribute is not JSON");
  }
  MeasuredShots out;
  out.bin_ns = config_number(config, "sensor", "bin_ns", place);
  out.pulse_sigma_ns = config_number(config, "sensor", "pulse_sigma_ns", place);
  out.band_names = nc.strings("band_name");
  const bool noisy = detector_enabled(config);
  const std::vector<std::size_t> shape = nc.shape("rx_waveform");
  if (shape.size() != 3 || shape[1] != out.band_names.size() || shape[2] < 2)
    throw input_error(place, "`rx_waveform` must be (shot, band, bin) with at least 2 bins");
  const std::size_t shots = shape[0], bands = shape[1], bins = shape[2];
  const std::vector<std::int64_t> numbers = nc.integers("shot_number");
  if (numbers.size() != shots) throw input_error(place, "`shot_number` must be (shot)");
  std::size_t begin = 0, end = shots;
  while (begin < shots && first && numbers[begin] < *first) ++begin;
  while (end > begin && last && numbers[end - 1] >= *last) --end;
  for (std::size_t i = begin; i < end; ++i)
    if ((first && numbers[i] < *first) || (last && numbers[i] >= *last))
      throw input_error(place, "its shot numbers are not in increasing order");
  const std::size_t count = end - begin;
  const auto per_shot = [&](const char* name) {
    if (!nc.has_variable(name)) return std::vector<double>(count, kNaN);
    std::vector<double> v = nc.doubles(name, {begin}, {count});
    return v;
  };
  const auto per_band = [&](const char* name) {
    if (!nc.has_variable(name)) return std::vector<double>(count * bands, kNaN);
    return nc.doubles(name, {begin, 0}, {count, bands});
  };
  const std::vector<double> lat = per_shot("lat"), lon = per_shot("lon"), elev = per_shot("elev"),
                            off_nadir = per_shot("off_nadir_deg"), bin0 = per_shot("elev_bin0"),
                            lastbin = per_shot("elev_lastbin"), flag = per_shot("quality_flag"),
                            beam = per_shot("beam"), cover = per_shot("cover_true"),
                            pai = per_shot("pai_true"), height = per_shot("canopy_height_true"),
                            pgap = per_shot("pgap_true");
  const std::vector<double> canopy = per_band("rx_energy_canopy"),
                            ground = per_band("rx_energy_ground");
  const std::vector<double> waveforms =
      count > 0 ? nc.doubles("rx_waveform", {begin, 0, 0}, {count, bands, bins})
                : std::vector<double>{};
  out.simulated = true;
  out.shots.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    MeasuredShot& s = out.shots[i];
    s.shot_number = numbers[begin + i];
    s.beam = std::isfinite(beam[i]) ? static_cast<int>(beam[i]) : 255;
    s.lat_deg = lat[i];
    s.lon_deg = lon[i];
    s.off_nadir_deg = std::isfinite(off_nadir[i]) ? off_nadir[i] : 0.0;
    s.axis = {out.bin_ns, bin0[i], lastbin[i]};
    s.good = flag[i] == 1.0 && std::isfinite(bin0[i]) && std::isfinite(lastbin[i]);
    for (std::size_t k = 0; k < bands; ++k) {
      const auto from = waveforms.begin() + static_cast<std::ptrdiff_t>((i * bands + k) * bins);
      s.waveform_W.emplace_back(from, from + static_cast<std::ptrdiff_t>(bins));
      for (double x : s.waveform_W.back())
        if (!std::isfinite(x)) s.good = false;
      const std::pair<double, double> noise =
          noisy ? end_noise(s.waveform_W.back()) : std::pair<double, double>{0.0, 0.0};
      s.noise_mean_W.push_back(noise.first);
      s.noise_sd_W.push_back(noise.second);
    }
    s.canopy_height_true_m = height[i];
    s.cover_true = cover[i];
    s.pai_true = pai[i];
    s.pgap_true = pgap[i];
    s.ground_elevation_true_m = elev[i];
    s.rhov_rhog_true = implied_rhov_rhog(canopy[i * bands], ground[i * bands], cover[i]);
  }
  return out;
}

void quiet_monte_carlo_noise(MeasuredShot& shot) {
  const std::vector<double>& w = shot.waveform_W.at(0);
  const double peak = *std::max_element(w.begin(), w.end()) - shot.noise_mean_W.at(0);
  if (shot.noise_sd_W[0] < 1e-3 * peak) shot.noise_mean_W[0] = shot.noise_sd_W[0] = 0.0;
}

namespace {

// --beams and --bbox: the shots in the beams named (each of which some input must hold) and
// inside the box (west > east crosses the antimeridian).
void select_shots(MeasuredShots& input, const RetrieveRequest& request) {
  if (!request.beams.empty()) {
    std::vector<int> held;
    for (const MeasuredShot& s : input.shots)
      if (std::find(held.begin(), held.end(), s.beam) == held.end()) held.push_back(s.beam);
    std::sort(held.begin(), held.end());
    for (int beam : request.beams) {
      if (std::find(held.begin(), held.end(), beam) != held.end()) continue;
      std::string names;
      for (int b : held)
        names += (names.empty() ? "" : ", ") + gedi_beam_group(static_cast<std::uint16_t>(b));
      throw config_error("--beams", gedi_beam_group(static_cast<std::uint16_t>(beam)) +
                                        " is in none of the inputs, whose shots are in " +
                                        (names.empty() ? std::string("no beam") : names));
    }
  }
  const auto kept = [&](const MeasuredShot& s) {
    if (!request.beams.empty() &&
        std::find(request.beams.begin(), request.beams.end(), s.beam) == request.beams.end())
      return false;
    if (!request.bbox_deg) return true;
    const auto [west, south, east, north] = *request.bbox_deg;
    const bool in_lon = west <= east ? s.lon_deg >= west && s.lon_deg <= east
                                     : s.lon_deg >= west || s.lon_deg <= east;
    return in_lon && s.lat_deg >= south && s.lat_deg <= north;
  };
  std::erase_if(input.shots, [&](const MeasuredShot& s) { return !kept(s); });
}

struct ShotResults {
  std::map<std::string, MethodEstimates> estimates;
  std::array<double, kL2bProfileBins> pavd_z{};
  RtResult rt;
  // L2A's default group a1 on its own (its RH98 and ground), beside the selected group: the
  // selection takes the lowest mode any group finds, which a5's 2 sigma may find in the
  // multiply scattered tail below the ground.
  double a1_rh98_m = kNaN, a1_ground_m = kNaN;
  // What gedi_l2b.h5 takes: the L2A group L2B ran on, its number, L2B's result.
  L2aGroupResult l2a{};
  int selected_algorithm = 0;
  GediL2bResult l2b = GediL2bResult::none({});
};

constexpr MethodEstimates kNone{kNaN, kNaN, kNaN, kNaN, kNaN, kNaN};

double median(std::vector<double> values) {
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2),
                   values.end());
  return values[values.size() / 2];
}

MethodEstimates rt_estimates(const RtResult& rt) {
  return {rt.canopy_height_m.mean,    rt.cover.mean,     rt.pai.mean,
          rt.ground_elevation_m.mean, rt.rhov_rhog.mean, rt.pgap.mean};
}

ShotResults retrieve_shot(const MeasuredShot& shot, double pulse_sigma_ns,
                          const std::vector<std::string>& methods, const RtInversion* rt) {
  ShotResults r;
  r.pavd_z.fill(kNaN);
  r.rt = RtResult::none();
  for (const std::string& m : methods) r.estimates[m] = kNone;
  if (shot.segment) {
    const Atl08Segment& a = *shot.segment;
    if (r.estimates.count("atl08"))
      r.estimates["atl08"] = {a.h_canopy_m, kNaN, kNaN, a.h_te_best_fit_m, kNaN, kNaN};
    // The ratio assumes canopy and ground reflect alike (rhov/rhog = 1); its PAI is L2B's formula
    // at nadir (G = 1/2, no clumping), as WI's is.
    const PhotonClassCounts& n = a.photons;
    if (r.estimates.count("photon_ratio") && n.canopy + n.top_of_canopy + n.ground > 0) {
      const double cover = photon_ratio_cover(n, 1.0).photon_ratio;
      // No ground photon: no gap seen, and no PAI that the ratio can tell.
      const double pai = cover < 1.0 ? -std::log(1.0 - cover) / 0.5 : kNaN;
      r.estimates["photon_ratio"] = {kNaN, cover, pai, kNaN, 1.0, 1.0 - cover};
    }
    if (rt && shot.photons) {
      const PhotonSegment& p = *shot.photons;
      r.rt = rt->invert_photons(
          {p.heights_m, p.pulses, p.background_rate_Hz, p.photons_per_J, a.h_te_best_fit_m});
      r.estimates["rt"] = rt_estimates(r.rt);
    }
    return r;
  }
  if (!shot.good) return r;
  const std::vector<double>& w = shot.waveform_W[0];
  const double peak = *std::max_element(w.begin(), w.end()) - shot.noise_mean_W[0];
  // A waveform without a detector has no noise: L2A's thresholds (multiples of sigma) then stand
  // on a floor of 1 % of the peak (its 6 sigma back threshold 6 %): lower, the lone rays of a
  // Monte Carlo shot of 10^3 rays scattered far below the ground (2 % of the peak at 20 m in
  // RetrieveCli's layers) were taken for the ground.
  const double sigma = shot.noise_sd_W[0] > 0.0 ? shot.noise_sd_W[0] : 0.01 * peak;
  const L2aResult l2a = process_l2a({w, shot.axis, shot.noise_mean_W[0], sigma});
  // L2A's granule's group and ground when one was given beside an L1B, else glaswave's selection.
  const L2aGroupResult selected = gedi_l2a_choice(l2a, shot.gedi, r.selected_algorithm);
  r.l2a = selected;
  const double zenith_rad = shot.off_nadir_deg * std::numbers::pi / 180.0;
  const bool want_l2b = r.estimates.count("gedi_l2b") || r.estimates.count("wi");
  GediL2bResult l2b = GediL2bResult::none({});
  if (want_l2b && selected.has_ground) {
    GediL2bInput in = l2b_input(w, shot.axis, shot.noise_mean_W[0], selected, zenith_rad);
    if (shot.gedi.has_l2a) in.l2a_quality_flag = in.l2a_quality_flag && shot.gedi.l2a_quality_flag;
    l2b = gedi_l2b(in);
  }
  r.l2b = l2b;
  if (r.estimates.count("gedi_l2a") && selected.has_ground)
    r.estimates["gedi_l2a"] = {selected.rh_m[98],          kNaN, kNaN,
                               selected.elev_lowestmode_m, kNaN, kNaN};
  if (r.estimates.count("gedi_l2a") && l2a.groups[0].has_ground) {
    r.a1_rh98_m = l2a.groups[0].rh_m[98];
    r.a1_ground_m = l2a.groups[0].elev_lowestmode_m;
  }
  if (r.estimates.count("gedi_l2b") && l2b.algorithmrun_flag) {
    r.estimates["gedi_l2b"] = {
        kNaN, l2b.cover, l2b.pai, selected.elev_lowestmode_m, l2b.rhov / l2b.rhog, l2b.pgap_theta};
    std::copy(l2b.pavd_z.begin(), l2b.pavd_z.end(), r.pavd_z.begin());
  }
  if (r.estimates.count("wi") && l2b.algorithmrun_flag) {
    // The seed's index on L2B's split of the return: (1 + WI) / 2 = Rv / (Rv + Rg) is the cover
    // when canopy and ground reflect alike (rhov/rhog = 1), and its PAI L2B's formula's.
    const double wi = waveform_index(l2b.rv, l2b.rg);
    const double cover = 0.5 * (1.0 + wi);
    r.estimates["wi"] = {kNaN, cover, -std::log(1.0 - cover) * std::cos(zenith_rad) / 0.5,
                         kNaN, 1.0,   1.0 - cover};
  }
  if (rt) {
    RtShot input;
    // A granule's counts on the table's scale, W.
    std::vector<std::vector<double>> in_W;
    input.noise_mean_W = shot.noise_mean_W;
    input.noise_sd_W = shot.noise_sd_W;
    if (shot.in_counts) {
      in_W = shot.waveform_W;
      for (std::vector<double>& band : in_W)
        for (double& x : band) x /= shot.counts_per_W;
      for (double& x : input.noise_mean_W) x /= shot.counts_per_W;
      for (double& x : input.noise_sd_W) x /= shot.counts_per_W;
    }
    for (const auto& band : in_W.empty() ? shot.waveform_W : in_W)
      input.waveform.emplace_back(band);
    input.axis = shot.axis;
    // The first guess of the ground: L2A's default group a1 (6 sigma back threshold), not the
    // selected one, which takes the lowest mode any group finds: a5's 2 sigma reaches lone
    // multiply scattered rays far below the ground in a noise-free Monte Carlo waveform.
    const L2aGroupResult& a1 = l2a.groups[0];
    input.ground_guess_m = a1.has_ground         ? a1.elev_lowestmode_m
                           : selected.has_ground ? selected.elev_lowestmode_m
                                                 : kNaN;
    r.rt = rt->invert(input);
    r.estimates["rt"] = rt_estimates(r.rt);
  }
  (void)pulse_sigma_ns;
  return r;
}

// retrieval.nc's variables, in its order: each one's name and unit, and where a method's
// estimate, rt's posterior and the simulation's truth keep it. One row a variable.
struct RetrievedVariable {
  const char* name;
  const char* units;
  double MethodEstimates::*estimate;
  RtStatistic RtResult::*posterior;
  double MeasuredShot::*truth;
};
constexpr RetrievedVariable kVariables[] = {
    {"canopy_height", "m", &MethodEstimates::canopy_height_m, &RtResult::canopy_height_m,
     &MeasuredShot::canopy_height_true_m},
    {"cover", "1", &MethodEstimates::cover, &RtResult::cover, &MeasuredShot::cover_true},
    {"pai", "1", &MethodEstimates::pai, &RtResult::pai, &MeasuredShot::pai_true},
    {"ground_elevation", "m", &MethodEstimates::ground_elevation_m, &RtResult::ground_elevation_m,
     &MeasuredShot::ground_elevation_true_m},
    {"rhov_rhog", "1", &MethodEstimates::rhov_rhog, &RtResult::rhov_rhog,
     &MeasuredShot::rhov_rhog_true},
    {"pgap", "1", &MethodEstimates::pgap, &RtResult::pgap, &MeasuredShot::pgap_true},
};
// rt's posterior beside its mean: each part's suffix and where RtStatistic keeps it.
constexpr std::pair<const char*, double RtStatistic::*> kPosteriorParts[] = {
    {"_rt_sd", &RtStatistic::sd}, {"_rt_p05", &RtStatistic::p05}, {"_rt_p95", &RtStatistic::p95}};

void write_product(const std::filesystem::path& path, const MeasuredShots& input,
                   const std::vector<ShotResults>& results, const std::vector<std::string>& methods,
                   const RetrieveRequest& request) {
  NetcdfFile nc = NetcdfFile::create(path);
  const std::size_t shots = input.shots.size();
  nc.define_dimension("shot", shots);
  nc.define_dimension("height", kL2bProfileBins);
  nc.put_text("", "Conventions", "CF-1.10");
  nc.put_text("", "title", "glaswave retrievals: each method's estimates per shot");
  nc.put_text("", "source", std::string("glaswave ") + GLASWAVE_VERSION);
  nc.put_text("", "history", request.command_line);
  // Appended in place: "," + a temporary string trips GCC 12's false -Wrestrict.
  auto join = [](const auto& items, auto text_of) {
    std::string out;
    for (const auto& item : items) {
      if (!out.empty()) out += ',';
      out += text_of(item);
    }
    return out;
  };
  nc.put_text("", "methods", join(methods, [](const std::string& m) { return m; }));
  nc.put_text("", "inputs",
              join(request.inputs, [](const std::filesystem::path& p) { return p.string(); }));
  if (request.table) nc.put_text("", "rt_table", request.table->string());
  nc.define_variable("shot_number", NC_INT64, {"shot"}, "", "the shot number");
  nc.define_variable("beam", NC_UBYTE, {"shot"}, "", "GEDI beam number (255: none)");
  nc.define_variable("lat", NC_DOUBLE, {"shot"}, "degrees_north", "footprint centre latitude");
  nc.put_text("lat", "standard_name", "latitude");
  nc.define_variable("lon", NC_DOUBLE, {"shot"}, "degrees_east", "footprint centre longitude");
  nc.put_text("lon", "standard_name", "longitude");
  nc.define_variable("height", NC_DOUBLE, {"height"}, "m",
                     "lower edge of the 5 m height bin above the ground");
  const std::string coordinates = "lat lon";
  for (const std::string& m : methods) {
    for (const RetrievedVariable& v : kVariables) {
      const std::string name = std::string(v.name) + "_" + m;
      nc.define_variable(name, NC_DOUBLE, {"shot"}, v.units,
                         std::string(v.name) + " retrieved by " + m);
      nc.put_text(name, "coordinates", coordinates);
      if (m != "rt") continue;
      for (const auto& [suffix, part] : kPosteriorParts) {
        const std::string extra = std::string(v.name) + suffix;
        nc.define_variable(extra, NC_DOUBLE, {"shot"}, v.units,
                           std::string(v.name) + " posterior " + (suffix + 4));
        nc.put_text(extra, "coordinates", coordinates);
      }
    }
  }
  const bool l2b = std::find(methods.begin(), methods.end(), "gedi_l2b") != methods.end();
  const bool rt = std::find(methods.begin(), methods.end(), "rt") != methods.end();
  const bool l2a = std::find(methods.begin(), methods.end(), "gedi_l2a") != methods.end();
  if (l2a) {
    nc.define_variable("canopy_height_gedi_l2a_a1", NC_DOUBLE, {"shot"}, "m",
                       "canopy_height retrieved by gedi_l2a's default group a1 (its RH98)");
    nc.define_variable("ground_elevation_gedi_l2a_a1", NC_DOUBLE, {"shot"}, "m",
                       "ground_elevation retrieved by gedi_l2a's default group a1");
    for (const char* name : {"canopy_height_gedi_l2a_a1", "ground_elevation_gedi_l2a_a1"})
      nc.put_text(name, "coordinates", coordinates);
  }
  if (l2b)
    nc.define_variable("pavd_z_gedi_l2b", NC_DOUBLE, {"shot", "height"}, "m^2 m^-3",
                       "plant area volume density per 5 m bin (GEDI L2B)");
  if (rt) {
    nc.define_variable("rt_flag", NC_UBYTE, {"shot"}, "", "what the rt table cannot explain");
    nc.put_bytes(
        "rt_flag", "flag_masks",
        {rt_misfit, rt_table_edge, rt_ground_search_edge, rt_not_run, rt_ground_off_guess});
    nc.put_text("rt_flag", "flag_meanings",
                "misfit table_edge ground_search_edge not_run ground_off_guess");
    nc.define_variable("rt_chi2_per_dof", NC_DOUBLE, {"shot"}, "1",
                       "best chi-squared per degree of freedom of the rt fit");
    // Where the best fit lies, so that it can be drawn over the shot: the table's entry
    // (`waveform` at `height` above the ground) and the ground it was placed on.
    nc.define_variable("rt_best_entry", NC_INT64, {"shot"}, "",
                       "the rt table's entry of the best fit (-1: none)");
    nc.define_variable("rt_best_ground_elevation", NC_DOUBLE, {"shot"}, "m",
                       "ground elevation of the rt best fit");
  }
  if (input.simulated) {
    for (const RetrievedVariable& v : kVariables)
      nc.define_variable(std::string(v.name) + "_true", NC_DOUBLE, {"shot"}, v.units,
                         std::string(v.name) + ": the simulation's truth");
  }
  nc.end_define();
  std::vector<std::int64_t> numbers(shots);
  std::vector<std::uint8_t> beams(shots);
  std::vector<double> lat(shots), lon(shots), heights(kL2bProfileBins);
  for (std::size_t i = 0; i < shots; ++i) {
    numbers[i] = input.shots[i].shot_number;
    beams[i] = static_cast<std::uint8_t>(std::clamp(input.shots[i].beam, 0, 255));
    lat[i] = input.shots[i].lat_deg;
    lon[i] = input.shots[i].lon_deg;
  }
  for (int k = 0; k < kL2bProfileBins; ++k) heights[k] = k * kL2bDz_m;
  nc.write("shot_number", numbers);
  nc.write("beam", beams);
  nc.write("lat", lat);
  nc.write("lon", lon);
  nc.write("height", heights);
  std::vector<double> column(shots);
  for (const std::string& m : methods) {
    for (const RetrievedVariable& v : kVariables) {
      for (std::size_t i = 0; i < shots; ++i) column[i] = results[i].estimates.at(m).*v.estimate;
      nc.write(std::string(v.name) + "_" + m, column);
      if (m != "rt") continue;
      for (const auto& [suffix, part] : kPosteriorParts) {
        for (std::size_t i = 0; i < shots; ++i) column[i] = (results[i].rt.*v.posterior).*part;
        nc.write(std::string(v.name) + suffix, column);
      }
    }
  }
  if (l2a) {
    for (std::size_t i = 0; i < shots; ++i) column[i] = results[i].a1_rh98_m;
    nc.write("canopy_height_gedi_l2a_a1", column);
    for (std::size_t i = 0; i < shots; ++i) column[i] = results[i].a1_ground_m;
    nc.write("ground_elevation_gedi_l2a_a1", column);
  }
  if (l2b) {
    std::vector<double> pavd;
    for (const ShotResults& r : results) pavd.insert(pavd.end(), r.pavd_z.begin(), r.pavd_z.end());
    nc.write("pavd_z_gedi_l2b", pavd);
  }
  if (rt) {
    std::vector<std::uint8_t> flags(shots);
    for (std::size_t i = 0; i < shots; ++i) {
      flags[i] = results[i].rt.flag;
      column[i] = results[i].rt.chi2_min / results[i].rt.dof;
    }
    nc.write("rt_flag", flags);
    nc.write("rt_chi2_per_dof", column);
    std::vector<std::int64_t> best(shots);
    for (std::size_t i = 0; i < shots; ++i) {
      best[i] = results[i].rt.best_entry;
      column[i] = results[i].rt.best_ground_elevation_m;
    }
    nc.write("rt_best_entry", best);
    nc.write("rt_best_ground_elevation", column);
  }
  if (input.simulated) {
    for (const RetrievedVariable& v : kVariables) {
      for (std::size_t i = 0; i < shots; ++i) column[i] = input.shots[i].*v.truth;
      nc.write(std::string(v.name) + "_true", column);
    }
  }
  nc.commit();
}

}  // namespace

RetrieveSummary run_retrieval(const RetrieveRequest& request,
                              const std::function<void(std::int64_t, std::int64_t)>& progress) {
  if (request.inputs.empty())
    throw config_error("INPUT",
                       "give at least one shots.nc, GEDI L1B, GLAH01 or ATL08 (and ATL03) granule");
  const auto named = [](const std::vector<std::string>& list, const std::string& m) {
    return std::find(list.begin(), list.end(), m) != list.end();
  };
  for (const std::string& m : request.methods) {
    if (!named(kWaveformMethods, m) && !named(kSegmentMethods, m))
      throw config_error("--methods", "unknown method \"" + m +
                                          "\": choose among gedi_l2a, gedi_l2b, wi, rt (waveforms) "
                                          "or atl08, photon_ratio (ATL08's segments)");
    if (std::count(request.methods.begin(), request.methods.end(), m) > 1)
      throw config_error("--methods", "\"" + m + "\" is given twice");
  }
  const std::filesystem::path out_dir =
      request.out_dir.empty() ? request.inputs.front().parent_path() : request.out_dir;
  const std::filesystem::path product = (out_dir.empty() ? "." : out_dir) / "retrieval.nc";
  if (std::filesystem::exists(product))
    throw config_error(product.string(), "exists already: give another --out");

  MeasuredShots input = read_retrieve_inputs(request.inputs, request.first_shot, request.last_shot);
  select_shots(input, request);
  // Every method the input allows by default; a method of the other kind is refused. rt reads
  // ICESat-2's photons from ATL03, given beside ATL08.
  std::vector<std::string> allowed = input.atl08 ? kSegmentMethods : kWaveformMethods;
  if (input.atl03) allowed.push_back("rt");
  std::vector<std::string> methods = request.methods;
  if (methods.empty()) {
    methods =
        input.atl08 ? kSegmentMethods : std::vector<std::string>{"gedi_l2a", "gedi_l2b", "wi"};
    if (request.table && (!input.atl08 || input.atl03)) methods.push_back("rt");
  }
  for (const std::string& m : methods) {
    if (named(allowed, m)) continue;
    if (input.atl08 && m == "rt")
      throw config_error("--methods",
                         "rt on ICESat-2 reads ATL03's photons: give the ATL03 granule beside "
                         "the ATL08");
    throw config_error("--methods", input.atl08
                                        ? "\"" + m +
                                              "\" reads waveforms, and ATL08 gives land "
                                              "segments: choose among atl08, photon_ratio, rt"
                                        : "\"" + m +
                                              "\" reads ATL08's land segments, and the "
                                              "input gives waveforms: choose among gedi_l2a, "
                                              "gedi_l2b, wi, rt");
  }
  const bool want_rt = named(methods, "rt");
  if (want_rt && !request.table)
    throw config_error("--methods", "rt needs --table TABLE.nc (made by `glaswave table`)");
  for (MeasuredShot& s : input.shots) {
    if (!s.in_counts) continue;
    if (request.counts_per_W) s.counts_per_W = *request.counts_per_W;
    if (want_rt && !std::isfinite(s.counts_per_W))
      throw config_error(
          "--counts-per-watt",
          "rt compares waveforms in watts with its table's, and a real granule "
          "does not say its digitiser's counts per watt: give it (docs/retrieval.md)");
  }
  for (MeasuredShot& s : input.shots) {
    if (!s.photons) continue;
    if (request.photons_per_J) s.photons->photons_per_J = *request.photons_per_J;
    if (want_rt && !std::isfinite(s.photons->photons_per_J))
      throw config_error("--photons-per-joule",
                         "rt compares photons with its table's returns in watts, and a real ATL03 "
                         "does not say how many photons a joule gives: give it "
                         "(docs/retrieval.md)");
  }
  const bool want_l2b_granule =
      input.gedi_l1b && std::find(methods.begin(), methods.end(), "gedi_l2b") != methods.end();
  const std::filesystem::path l2b_granule = (out_dir.empty() ? "." : out_dir) / "gedi_l2b.h5";
  if (want_l2b_granule && std::filesystem::exists(l2b_granule))
    throw config_error(l2b_granule.string(), "exists already: give another --out");
  const int cores = tbb::this_task_arena::max_concurrency();
  tbb::task_arena arena(request.threads > 0 ? std::min(request.threads, cores) : cores);
  std::optional<ForwardTable> table;
  std::optional<RtInversion> rt;
  if (want_rt) {
    table = read_table(*request.table);
    RtSettings settings = request.rt;
    // Photons have a tempering of their own (calibrate_photons, below): the waveforms' (20 s of
    // CPU on 1500 entries) is not needed.
    if (input.atl03 && settings.tempering == 0.0) settings.tempering = 1.0;
    arena.execute([&] {  // its calibration on --threads
      rt.emplace(*table, settings);
      // The photons' tempering for the segments' median pulses, scale and background.
      if (input.atl03) {
        std::vector<double> pulses, per_J, rate;
        for (const MeasuredShot& s : input.shots)
          if (s.photons) {
            pulses.push_back(s.photons->pulses);
            per_J.push_back(s.photons->photons_per_J);
            rate.push_back(s.photons->background_rate_Hz);
          }
        if (!pulses.empty()) rt->calibrate_photons(median(pulses), median(per_J), median(rate));
      }
    });
    // Photons have no bins: a table's of any width counts them.
    rt->check_compatible(input.band_names, input.atl03 ? table->bin_ns : input.bin_ns,
                         input.pulse_sigma_ns, request.table->string());
  }
  std::filesystem::create_directories(out_dir.empty() ? "." : out_dir);

  const std::int64_t shots = static_cast<std::int64_t>(input.shots.size());
  std::vector<ShotResults> results(input.shots.size());
  std::atomic<std::int64_t> done{0};
  std::mutex progress_mutex;
  const auto started = std::chrono::steady_clock::now();
  arena.execute([&] {
    tbb::parallel_for(std::int64_t{0}, shots, [&](std::int64_t i) {
      results[i] =
          retrieve_shot(input.shots[i], input.pulse_sigma_ns, methods, rt ? &*rt : nullptr);
      const std::int64_t finished = ++done;
      if (progress && finished % 64 == 0) {
        std::lock_guard lock(progress_mutex);
        progress(finished, shots);
      }
    });
  });
  RetrieveSummary summary;
  summary.wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  write_product(product, input, results, methods, request);
  if (want_l2b_granule) {
    std::vector<GediL2bShot> granule;
    for (std::size_t i = 0; i < input.shots.size(); ++i) {
      const MeasuredShot& s = input.shots[i];
      if (!s.gedi.present) continue;
      const ShotResults& r = results[i];
      granule.push_back({static_cast<std::uint64_t>(s.shot_number), s.gedi, s.axis,
                         s.waveform_W.empty() ? 0 : s.waveform_W[0].size(), r.selected_algorithm,
                         r.l2a,
                         static_cast<std::uint8_t>(r.l2a.has_ground && s.good &&
                                                   (!s.gedi.has_l2a || s.gedi.l2a_quality_flag)),
                         s.gedi.has_l2a ? s.gedi.l2a_sensitivity : kNaN, r.l2b});
    }
    write_gedi_l2b(l2b_granule, granule, request.command_line);
    summary.l2b_granule = l2b_granule;
  }
  summary.shots = shots;
  summary.methods = methods;
  summary.product = product;
  for (const ShotResults& r : results) summary.rt_flagged += want_rt && r.rt.flag != 0;
  if (rt && input.atl03) summary.rt_photon_tempering = rt->photon_tempering();
  return summary;
}

}  // namespace glaswave
