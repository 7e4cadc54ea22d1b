// GEDI L1B- and L2A-style granules (PRODUCT.md section 10): DIR/gedi_l1b.h5 and DIR/gedi_l2a.h5
// in the layout of GEDI01_B and GEDI02_A (groups BEAMxxxx at the root, the dictionaries' names,
// dtypes, units and 1-based indices, delta_time from 2018-01-01T00:00:00Z), read by rGEDI's
// getLevel1BWF and getLevel2AM as they read the real ones. The simulation's truth is in each
// beam's group `glaswave_truth`. docs/granules.md lists every path and its source.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "pipeline/products/hdf5_granule_writer.hpp"

namespace glaswave {

// GEDI's epoch, 2018-01-01T00:00:00Z, in seconds since 2000-01-01T12:00:00Z (no leap seconds).
inline constexpr double kGediEpochS = 568036800.0;
// ancillary/master_time_epoch: the GPS seconds of GEDI's epoch (18 leap seconds by 2018).
inline constexpr double kGediMasterTimeEpoch = 1198800018.0;
// GEDI's eight beams, in the order of the beam numbers.
inline constexpr std::uint16_t kGediBeams[8] = {0, 1, 2, 3, 5, 6, 8, 11};
// Each beam's BEAMxxxx/channel as real L1B files number it: the two coverage beams a laser's
// dithering splits share a channel (BEAM0000 and BEAM0001 0, BEAM0010 and BEAM0011 1), each
// full-power beam has its own (BEAM0101 2, BEAM0110 3, BEAM1000 4, BEAM1011 5).
inline constexpr std::uint8_t kGediChannels[8] = {0, 0, 1, 1, 2, 3, 4, 5};
// The group of a shot whose track gives no beam (a synthetic track): a full-power beam, as the
// sensor's pulse energy is a whole laser's.
inline constexpr std::uint16_t kGediDefaultBeam = 5;

enum class GediLevel : std::uint8_t { l1b, l2a };

class GediGranuleWriter : public Hdf5GranuleWriter {
 public:
  // Writes the band nearest 1064 nm, GEDI's one.
  GediGranuleWriter(const std::filesystem::path& final_path, GediLevel level, const RunInfo& info);

 private:
  struct Shot {
    std::uint16_t beam = kGediDefaultBeam;
    std::uint8_t degrade = 0, quality = 0, modes = 0;
    std::uint64_t shot_number = 0;
    double delta_time = 0, dem = 0, elev_bin0 = 0, elev_lastbin = 0;
    LatLon bin0{}, lastbin{}, lowest{}, highest{}, lowest_return{};
    double elev_lowest_return = 0;  // the signal's end
    double solar_elevation = 0, solar_azimuth = 0, elev_lowest = 0, elev_highest = 0;
    double sensitivity = 0, noise_mean = 0, noise_stddev = 0, rx_energy = 0;
    double cover = 0, pai = 0, height = 0, pgap = 0, energy_canopy_J = 0, energy_ground_J = 0;
    std::vector<float> rx, rx_canopy, rx_ground, rh;
  };
  void keep(std::int64_t index, const ShotRecord& shot) override;
  void write_file(Hdf5Writer& file) override;
  Hdf5Chunking chunking() const override { return Hdf5Chunking::every; }
  // What both levels' beam groups begin with: shot_number, delta_time, beam, channel.
  static void write_shot_ids(Hdf5Writer& file, const std::string& group,
                             const std::vector<const Shot*>& shots, const char* delta_time_meaning);
  void write_l1b_beam(Hdf5Writer& file, const std::string& group,
                      const std::vector<const Shot*>& shots);
  void write_l2a_beam(Hdf5Writer& file, const std::string& group,
                      const std::vector<const Shot*>& shots);
  static void write_l2a_algorithm(Hdf5Writer& file, const std::string& group,
                                  const std::vector<const Shot*>& shots);

  GediLevel level_;
  std::size_t band_;
  std::vector<float> tx_counts_;
  double pulse_sigma_bins_ = 0;
  std::vector<Shot> shots_;
};

// BEAMxxxx: the beam's number in four binary digits (5 -> "BEAM0101").
std::string gedi_beam_group(std::uint16_t beam);

// GEDI L2A's sensitivity as glaswave makes it (GEDI's own needs the instrument's calibration):
// the largest canopy cover whose ground return would still stand `kSensitivitySigmas` noise
// standard deviations above the noise at its peak, for a return of the waveform's whole energy:
// 1 - k sigma_noise sqrt(2 pi) sigma_pulse / E, E the noise-subtracted energy (counts over the
// bins), sigma_pulse the transmitted pulse's RMS width in bins. 1 without noise, fill (-9999)
// without a return.
inline constexpr double kSensitivitySigmas = 4.0;
double gedi_sensitivity(double noise_stddev, double pulse_sigma_bins, double energy_counts);

}  // namespace glaswave
