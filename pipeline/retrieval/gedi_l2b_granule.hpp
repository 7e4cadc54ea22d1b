// DIR/gedi_l2b.h5, the GEDI L2B algorithm's results in the layout of GEDI02_B (PRODUCT.md
// section 11, issue 37 item 2): per beam group BEAMxxxx the paths, dtypes and shapes of the real
// product (the GEDI L2B data dictionary, LP DAAC doi 10.5067/GEDI/GEDI02_B.002, checked against
// the real GEDI02_B subset rGEDI ships,
// inst/extdata/GEDI02_B_2019108080338_O01964_T05337_02_001_01_sub.zip), so that rGEDI's
// readLevel2B, getLevel2BVPM, getLevel2BPAIProfile and getLevel2BPAVDProfile
// (carlos-alberto-silva/rGEDI R/getLevel2BVPM.R, R/getLevel2BPAIProfile.R,
// R/getLevel2BPAVDProfile.R) read it as they read a real one. docs/granules.md lists the paths.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "pipeline/products/gedi_l2a_groups.hpp"
#include "pipeline/products/gedi_l2b_algorithm.hpp"

namespace glaswave {

// What a GEDI L1B granule (and the L2A beside it, when given) says of one shot beyond its
// waveform: the L2B granule carries it through. NaN where the input has none.
struct GediShotInfo {
  bool present = false;  // the shot came from a GEDI L1B granule
  std::uint16_t beam = 0;
  std::uint8_t channel = 0;
  double delta_time_s = 0.0;  // since 2018-01-01T00:00:00Z
  double lat_bin0_deg = 0.0, lon_bin0_deg = 0.0, lat_lastbin_deg = 0.0, lon_lastbin_deg = 0.0;
  double solar_elevation_deg, solar_azimuth_deg, dem_m, local_beam_elevation_rad,
      local_beam_azimuth_rad;
  std::int8_t degrade_flag = 0;
  // From the L2A granule given beside the L1B (has_l2a): its selected group (1..6, 0 none), its
  // ground and highest return, quality flag and sensitivity.
  bool has_l2a = false;
  int l2a_selected_algorithm = 0;
  double l2a_elev_lowestmode_m, l2a_elev_highestreturn_m, l2a_sensitivity;
  std::uint8_t l2a_quality_flag = 0;
};

// One shot of gedi_l2b.h5: where it lies, the L2A group the L2B algorithm ran on and its result.
struct GediL2bShot {
  std::uint64_t shot_number = 0;
  GediShotInfo info;
  WaveformAxis axis;  // the received waveform's bins
  std::size_t bins = 0;
  int selected_algorithm = 0;  // 1..6, 0 when no group found a ground
  L2aGroupResult l2a;          // the selected group's (ground, begin, end, rh)
  std::uint8_t l2a_quality_flag = 0;
  double sensitivity;  // L2A's when given, else fill
  GediL2bResult l2b;
};

// The real product's fill value of its floating-point and int16 fields.
inline constexpr double kGediL2bFill = -9999.0;

// The real product's channel of a beam, as the real GEDI02_B subset in rGEDI gives it (issue
// 38): BEAM0001 -> 0, BEAM0010 and BEAM0011 -> 1, BEAM0101 -> 2, BEAM0110 -> 3, BEAM1000 -> 4,
// BEAM1011 -> 5. BEAM0000, absent from that subset, is taken as 0 (the first coverage beam).
std::uint8_t gedi_real_channel(std::uint16_t beam);

// Writes `path` (under PATH.part, renamed when complete): one group BEAMxxxx a beam, in the
// order of the beam numbers, its shots in the order given. Hold no NetCDF/HDF5 lock: it takes
// netcdf_library_mutex() itself.
void write_gedi_l2b(const std::filesystem::path& path, const std::vector<GediL2bShot>& shots,
                    const std::string& history);

}  // namespace glaswave
