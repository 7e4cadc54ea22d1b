// The keys of the lidar and the air it looks through: `sensor`, `detector`, `atmosphere`.
#include "core/part_kind.hpp"
#include "footprints/atmosphere_settings.hpp"
#include "footprints/receiver_traits.hpp"
#include "pipeline/config/atmosphere_presets.hpp"
#include "pipeline/config/config.hpp"
#include "pipeline/config/key_fields.hpp"
#include "pipeline/config/presets.hpp"

namespace glaswave::section_keys {

using nlohmann::json;
using namespace declare;

namespace {

std::vector<std::string> preset_names() {
  std::vector<std::string> names;
  for (const auto& [name, text] : sensor_presets()) names.push_back(name);
  return names;
}

// sensor.receiver's: each receiver's own words (core/part_kind.hpp: the receivers declare their
// kinds), then the presets that choose one.
std::string receiver_description() {
  const auto receivers = Registry<PartKind<ReceiverTraits>>::instance().entries();
  std::vector<std::string> kinds;
  for (const auto& receiver : receivers)
    kinds.push_back("`" + receiver.name + "` (" + receiver.make.description + ")");
  std::string text = "what the record is made of: " + alternatives(kinds);
  for (const auto& [name, preset] : sensor_presets()) {
    const json receiver = json::parse(preset).value("receiver", json());
    if (receiver.is_string())
      text += "; the `" + name + "` preset's is `" + receiver.get<std::string>() + "`";
  }
  return text;
}

}  // namespace

Key sensor_keys() {
  const Fields<SensorSettings> s;
  using S = SensorSettings;
  Key preset = choice("preset", std::nullopt, preset_names(),
                      "`north2010` (the seed's Table 2, exactly), `glas` (the same with "
                      "GLAS's ~70 m beam), `gedi` (GEDI's power beam: 1064 nm, 15.6 ns FWHM, "
                      "~25 m from 420 km; set `track.altitude_m` to 420000) or `atlas` (ICESat-2's "
                      "strong beam: 532 nm, 1.5 ns FWHM, ~11 m from 496 km; set "
                      "`track.altitude_m` to 496000; docs/icesat2.md); keys beside it "
                      "override it (`bands` as a whole); absent: the values of `north2010`");
  preset.default_text = "none";
  return object(
      "sensor", "the lidar (the seed's Table 2)",
      {s.bind(std::move(preset), &S::preset,
              [](JsonReader& r, const std::string& key) {
                return r.optional_string(key).value_or("");
              }),
       // Up to 1 MHz: ATLAS fires 10 kHz, airborne scanners hundreds of kHz.
       s.number("pulse_rate_hz", &S::pulse_rate_hz, open_closed(0, 1e6), "Hz",
                "the laser's pulse rate (GLAS 40, GEDI 242, ATLAS 10 000): the shot rate of a "
                "track that gives no `rate_hz`, and so its shots' times and, without "
                "`spacing_m`, their spacing"),
       // 1 ps to 1 us: shorter would put the whole pulse energy into an infinite power; longer is
       // no longer a ranging pulse.
       s.number("pulse_sigma_ns", &S::pulse_sigma_ns, closed(0.001, 1000), "ns",
                "RMS width of the Gaussian pulse"),
       s.number("divergence_sigma_rad", &S::divergence_sigma_rad,
                open_closed(0, run_limits::angle_rad), "rad",
                "beam angular RMS width per axis (intensity ∝ exp(−θ²/2σ²))"),
       s.choice("beam_profile", &S::beam_profile, {"gaussian", "uniform"},
                "the beam's intensity across it: `gaussian` (∝ exp(−θ²/2σ²)) or `uniform` (the "
                "same over a cone of half-angle 2 `divergence_sigma_rad`: the same RMS per axis, "
                "its edge at the Gaussian's 1/e² contour; RAMI-IV's lidar footprint)"),
       s.number("ifov_rad", &S::ifov_rad, open_closed(0, run_limits::angle_rad), "rad",
                "detector full field of view (top-hat cone); the scene a shot builds grows with "
                "it (see Limits)"),
       // The largest telescopes built are about 80 m²; far beyond, received powers overflow.
       s.number("telescope_area_m2", &S::telescope_area_m2, open_closed(0, 100), "m²",
                "receiver aperture"),
       // 1 ps to 1 ms a bin: a window of bins beyond either end is no waveform.
       s.number("bin_ns", &S::bin_ns, closed(0.001, 1e6), "ns", "width of a recording bin"),
       s.integer("bins", &S::bins, 1, run_limits::waveform_bins, "",
                 "recording bins; the return from the footprint centre falls two thirds into the "
                 "window"),
       object_array("bands", json::parse(sensor_presets().at(default_sensor_preset))["bands"],
                    "the laser's bands: 532 and 1064 nm by default, with pulse energies of 32 and "
                    "72 mJ and round-trip transmissions of 0.8 and 0.9",
                    {string("name", std::nullopt,
                            "the band's name: the key of per-band values; unique, not empty")
                         .with_required(),
                     // Ultraviolet to far infrared: what a lidar through the atmosphere uses, and
                     // photon energies that stay finite.
                     number("wavelength_nm", std::nullopt, closed(100, 100000), "nm", "wavelength")
                         .with_required(),
                     // Spaceborne lasers fire tens of mJ, the largest research lasers a few kJ.
                     number("pulse_energy_mJ", std::nullopt, open_closed(0, 1e7), "mJ",
                            "energy of a transmitted pulse")
                         .with_required(),
                     number("atmos_transmission_roundtrip", std::nullopt, open_closed(0, 1), "",
                            "two-way transmission of the atmosphere; required without "
                            "`atmosphere`, refused beside it (its layers give it)")})
           .with_items(1, run_limits::bands)
           .with_default_text("the preset's"),
       s.choice("receiver", &S::receiver, declared_kinds<ReceiverTraits>(), receiver_description()),
       s.string_array("beams", &S::beams,
                      "photon counting: which of ATLAS's beams `gt1l gt1r gt2l gt2r gt3l gt3r` to "
                      "simulate (strong: the `l` beams backward, the `r` ones forward; weak: the "
                      "others, at 45/175 of the energy), each on its own ground track about the "
                      "`pass`'s reference track; several only on a `pass`"),
       s.choice("sc_orient", &S::sc_orient, {"backward", "forward"},
                "photon counting: the spacecraft's orientation (ATL03's `orbit_info/sc_orient` "
                "0 or 1): `backward` makes the `l` beam of each pair strong and `gt1l` ... "
                "`gt3r` ATLAS's spots 1 ... 6, `forward` the `r` beams strong and the spots 6 "
                "... 1"),
       s.number("photon_efficiency", &S::photon_efficiency, open_closed(0, 1), "",
                "photon counting: the receiver's optical throughput times its detectors' photon "
                "detection efficiency (ATLAS: 0.45 × 0.15)"),
       s.number("filter_bandwidth_nm", &S::filter_bandwidth_nm, above(0), "nm",
                "photon counting: the receiver filter's equivalent width (the solar background "
                "grows with it)"),
       s.number("dead_time_ns", &S::dead_time_ns, at_least(0), "ns",
                "photon counting: each detector channel's non-paralysable dead time (16 channels "
                "a strong beam, 4 a weak one)")});
}

Key atmosphere_keys() {
  const Fields<AtmosphereLayer> l;
  using L = AtmosphereLayer;
  // Heights: the shore of the Dead Sea lies 430 m below the ellipsoid; the atmosphere ends near
  // 100 km.
  const Range heights = closed(-1000, 100000);
  const auto height = [&](const char* name, double L::*member, const char* description) {
    return l.bind(number(name, std::nullopt, heights, "m", description).with_required(), member,
                  [](JsonReader& r, const std::string& key) { return r.number(key); });
  };
  Key phase = make("phase", KeyType::choice_or_object, "",
                   "the layer's phase function: `rayleigh` (molecules), `{\"hg_g\": g}` "
                   "(Henyey–Greenstein of asymmetry g) or `{\"hg2\": [g1, g2, w]}` (w HG(g1) + "
                   "(1 − w) HG(g2), a forward and a backward peak)");
  phase.choices = {"rayleigh"};
  phase.required = true;
  phase.children = {
      number("hg_g", std::nullopt, open(-1, 1), "", "Henyey–Greenstein asymmetry g"),
      number_tuple("hg2", {{"g1", open(-1, 1)}, {"g2", open(-1, 1)}, {"w", closed(0, 1)}}, "",
                   "two-term Henyey–Greenstein: the asymmetries of its two terms and the weight "
                   "of the first")};
  Key atmosphere =
      make("atmosphere", KeyType::choice_or_object, "",
           "the atmosphere's layers on the light's path (docs/physics.md): a preset's name, or "
           "an object. With it, each band's two-way transmission comes from the layers (give "
           "no `sensor.bands[].atmos_transmission_roundtrip` beside it); absent: each band's "
           "fixed `atmos_transmission_roundtrip`, as before");
  atmosphere.default_text = "none";
  atmosphere.choices = atmosphere_preset_names();
  Key preset =
      choice("preset", std::nullopt, atmosphere_preset_names(),
             "`clear` (molecules and a clean continental aerosol, τ 0.064 at 550 nm), "
             "`haze` (molecules and a polluted one, τ 0.327), `cirrus` (`clear` and a "
             "cirrus of τ 0.3 at 9–11 km above the ellipsoid) or `stratus` (`clear` "
             "and a stratus of τ 2 at 0.5–1.5 km above the ground), expanded for the "
             "bands' wavelengths (docs/guide/atmosphere.md); `layers` beside it replace its own");
  preset.default_text = "none";
  // Beyond an optical depth of 50 the two-way transmission is below 1e-43.
  Key optical_depth = spectral("optical_depth", 0.0, closed(0, 50), "",
                               "the layer's vertical extinction optical depth");
  optical_depth.default_value = nullptr;
  optical_depth.required = true;
  atmosphere.children = {
      std::move(preset),
      object_array(
          "layers", nullptr,
          "horizontally uniform layers, which may overlap; the preset's when not given",
          {height("base_m", &L::base_m, "the layer's base"),
           height("top_m", &L::top_m, "the layer's top, above its base"),
           l.choice_of("above", &L::above_ellipsoid, {{"ground", false}, {"ellipsoid", true}},
                       "what the heights are measured from: the ground under the footprint "
                       "centre, or the WGS84 ellipsoid"),
           std::move(optical_depth),
           spectral("single_scattering_albedo", 1.0, closed(0, 1), "",
                    "the part of the extinction that scatters"),
           std::move(phase)})
          .with_items(1, std::numeric_limits<std::size_t>::max())
          .with_default_text("the preset's")};
  return atmosphere;
}

Key detector_keys() {
  const Fields<DetectorSettings> d;
  using S = DetectorSettings;
  return object(
      "detector",
      "the receiver between the light and the recorded waveform, to make waveforms that look "
      "like GLAS's; off by default. Levels are in W at the detector's input and `rx_waveform` "
      "stays in W; its noise is keyed by (seed, shot, band, bin), the same for any threads or "
      "split. The truth parts `rx_waveform_canopy`/`_ground` stay noise-free",
      {d.boolean("enabled", &S::enabled, "whether the detector applies"),
       // Levels at the detector: returns are microwatts; a watt of light or noise is already far
       // beyond any detector, and larger levels overflow the products.
       d.number("background_W", &S::background_W, closed(0, 1), "W",
                "mean background light (a sunlit scene)"),
       d.boolean("photon_noise", &S::photon_noise,
                 "Poisson statistics of signal and background photons, hν from each band's "
                 "wavelength"),
       d.number("quantum_efficiency", &S::quantum_efficiency, open_closed(0, 1), "",
                "photoelectrons per photon, for `photon_noise`"),
       d.number("noise_rms_W", &S::noise_rms_W, closed(0, 1), "W", "Gaussian detector noise, RMS"),
       // Photomultipliers reach 1e8; 1e12 leaves the products finite.
       d.number("gain", &S::gain, open_closed(0, 1e12), "", "amplification before the digitiser"),
       d.integer("bits", &S::bits, 0, 32, "", "digitiser resolution; 0: not digitised"),
       d.number("saturation_W", &S::saturation_W, open_closed(0, 1e12), "W",
                "the digitiser's full scale after the gain; required with `bits`; output above it "
                "clips, below 0 reads 0")
           .with_default_text("none")});
}

}  // namespace glaswave::section_keys
