// `glaswave retrieve` (PRODUCT.md section 11): measured shots in, each method's estimates out,
// side by side in DIR/retrieval.nc with the truth of simulated input. Reads glaswave's own
// shots.nc, GEDI L1B granules with their L2A, GLAH01 granules with their GLAH14 and ATL08
// granules with their ATL03 (retrieve_inputs.hpp), and writes DIR/gedi_l2b.h5 for GEDI L1B input
// (gedi_l2b_granule.hpp); the methods are GEDI L2A's six groups and selected one (gedi_l2a),
// GEDI L2B (gedi_l2b), the seed's waveform index (wi), ATL08's own (atl08), the photon ratio
// (photon_ratio) and the physically based inversion over a forward table (rt), on waveforms or
// on ATL03's photons.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/products/canopy_indices.hpp"
#include "pipeline/retrieval/gedi_l2b_granule.hpp"
#include "pipeline/retrieval/rt_inversion.hpp"

namespace glaswave {

// The methods of waveforms, and of ATL08's land segments.
inline const std::vector<std::string> kWaveformMethods = {"gedi_l2a", "gedi_l2b", "wi", "rt"};
inline const std::vector<std::string> kSegmentMethods = {"atl08", "photon_ratio"};

struct RetrieveRequest {
  std::vector<std::filesystem::path> inputs;
  std::filesystem::path out_dir;                      // empty: the first input's folder
  std::optional<std::filesystem::path> table;         // needed by rt
  std::vector<std::string> methods;                   // empty: every method the input allows
  std::optional<std::int64_t> first_shot, last_shot;  // shot numbers [A, B)
  std::vector<int> beams;                             // --beams: beam numbers kept; empty: all
  std::optional<std::array<double, 4>> bbox_deg;      // --bbox: west, south, east, north
  std::optional<double> counts_per_W;                 // --counts-per-watt: granules' scale
  std::optional<double> photons_per_J;                // --photons-per-joule: ATL03's scale
  int threads = 0;                                    // 0: every core
  std::string command_line;
  RtSettings rt;
};

struct RetrieveSummary {
  std::int64_t shots = 0;
  std::vector<std::string> methods;
  std::int64_t rt_flagged = 0;  // shots with rt_flag != 0
  double wall_s = 0.0;          // the methods on the shots, reading and writing left out
  std::filesystem::path product;
  std::filesystem::path l2b_granule;  // DIR/gedi_l2b.h5 for GEDI L1B input, else empty
  // rt on ATL03's photons: the tempering calibrated on the table (NaN otherwise).
  double rt_photon_tempering = std::numeric_limits<double>::quiet_NaN();
};

// An ICESat-2 ATL08 land segment, which atl08 input gives in place of a waveform: ATL08's own
// canopy height (h_canopy, above the terrain) and best-fit terrain, and its photons by class.
struct Atl08Segment {
  double h_canopy_m, h_te_best_fit_m;
  PhotonClassCounts photons;
  std::int64_t segment_id_end = 0;  // its last 20 m ATL03 segment (segment_id_beg the first)
  double terrain_slope = 0.0;       // along track, rise over run (ATL08's; 0 where it has none)
};

// ATL03's photons over an ATL08 land segment (ATL03 given beside ATL08), what rt reads of
// ICESat-2: their heights with the segment's along-track terrain slope taken out about the
// middle of their span, the pulses fired over the segment, the background rate over its time
// (ATL03's bckgrd_atlas) and the photons a joule of the table's return gives (glaswave's truth;
// NaN in a real granule, which does not say).
struct PhotonSegment {
  std::vector<double> heights_m;
  double pulses = 0.0;
  double background_rate_Hz = 0.0;
  double photons_per_J = std::numeric_limits<double>::quiet_NaN();
};

// One measured shot as the methods read it: band 0 for the missions' algorithms, every band for
// rt.
struct MeasuredShot {
  std::int64_t shot_number = 0;
  int beam = 0;
  double lat_deg = 0.0, lon_deg = 0.0, off_nadir_deg = 0.0;
  std::vector<std::vector<double>> waveform_W;  // [band][bin]
  WaveformAxis axis;
  std::vector<double> noise_mean_W, noise_sd_W;  // [band]
  bool good = true;
  // Truth of simulated input (NaN otherwise).
  double canopy_height_true_m, cover_true, pai_true, ground_elevation_true_m, rhov_rhog_true;
  double pgap_true = std::numeric_limits<double>::quiet_NaN();
  // The waveform's and its noise's units per watt: 1 for shots.nc (W); a granule's digitiser
  // counts per watt (in_counts), NaN where the granule does not say (a real one).
  double counts_per_W = 1.0;
  bool in_counts = false;
  std::optional<Atl08Segment> segment;   // ATL08 input: a land segment, and no waveform
  std::optional<PhotonSegment> photons;  // and ATL03's photons over it, when given beside
  GediShotInfo gedi;                     // GEDI L1B input's (present) and its L2A's
};

struct MeasuredShots {
  std::vector<std::string> band_names;
  double bin_ns = 0.0;
  double pulse_sigma_ns = 0.0;
  bool simulated = true;
  bool gedi_l1b = false;  // read from a GEDI L1B granule: gedi_l2b.h5 is written
  bool atl08 = false;     // ATL08's land segments: the methods atl08 and photon_ratio
  bool atl03 = false;     // and ATL03's photons over them: rt too
  std::vector<MeasuredShot> shots;
};

// Reads glaswave's shots.nc (shot numbers [first, last) when given): its waveforms, where they
// lie, each band's noise (the quieter end of the window's mean and sd where the run's detector
// was on, else 0: a simulation without a detector has none) and the truth. An input error naming
// the file when it is not one.
MeasuredShots read_shots(const std::filesystem::path& file, std::optional<std::int64_t> first,
                         std::optional<std::int64_t> last);

// A simulated granule's shot without a detector: its "noise" is the Monte Carlo's few rays
// before the signal (a sd of 1e-5 of the peak), which L2A's thresholds would take for a
// detector's and so find the ground among lone rays far below. Under 1e-3 of the peak (no
// detector is that quiet) it is set to none, as shots.nc without a detector has.
void quiet_monte_carlo_noise(MeasuredShot& shot);

// Each method's estimates of one shot: V per method, NaN where a method gives none.
struct MethodEstimates {
  double canopy_height_m, cover, pai, ground_elevation_m, rhov_rhog;
  double pgap;  // the vertical gap probability: L2B's Pgap, one less WI's cover, rt's
};

RetrieveSummary run_retrieval(const RetrieveRequest& request,
                              const std::function<void(std::int64_t, std::int64_t)>& progress);

}  // namespace glaswave
