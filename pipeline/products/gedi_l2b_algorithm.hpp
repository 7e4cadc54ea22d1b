// GEDI L2B's canopy cover and vertical profile metrics of one received waveform (Tang & Armston,
// GEDI L2B ATBD; the L2B data dictionary's names), from L2A's selected signal begin and end and
// ground (the lowest mode), with the mission's assumptions as defaults:
// - Ground and canopy returns by the half-energy method: the ground return is taken as symmetric
//   about the lowest mode, so Rg is twice the energy between the lowest mode and the signal's end,
//   and the canopy return is the waveform above the lowest mode less the mirror image of the
//   waveform below it (negative differences, noise, set to 0): Rv = the energy from the signal's
//   begin to its end less Rg.
// - Pgap(theta) = 1 - Rv / (Rv + (rhov / rhog) Rg): a fixed ratio of canopy to ground
//   reflectance, rhov / rhog = 0.6 / 0.4 = 1.5 in every shot of the real product.
// - cover = 1 - Pgap; PAI = -ln(Pgap) cos(theta) / (G Omega), G = 0.5 (rossg, random leaf
//   angles), Omega = 1 (omega, foliage placed at random: no clumping); theta the beam's zenith.
// - Profiles, cumulative from the top: Pgap(z) = 1 - Rv(z) / (Rv + (rhov / rhog) Rg), Rv(z) the
//   canopy return above height z over the ground (Rv(z <= 0) = Rv); cover_z[k] = 1 - Pgap(z_k)
//   and pai_z[k] the PAI above z_k = k dz, so cover_z[0] = cover and pai_z[0] = pai; pavd_z[k] =
//   (pai_z[k] - pai_z[k + 1]) / dz, the PAI inside [z_k, z_k + dz) per metre (-dPAI/dz over the
//   bin), so sum(pavd_z) dz = pai for a canopy below 30 dz; dz = 5 m, 30 bins, as the product.
// - fhd_normal = -sum p_k ln p_k with p_k = pavd_z[k] dz / sum(pavd_z dz), over p_k > 0.
// Flags: algorithmrun_flag 1 when the inputs allow the algorithm to run (a finite waveform,
// finite begin, ground and end in that order, energy above the noise); l2b_quality_flag 1 when it
// ran, L2A's shot is good, a ground return was measured (Rg > 0: Pgap > 0, PAI finite) and Rv >= 0.
// The real flags also weigh the beam's sensitivity and degraded geolocation, which the caller
// knows and may fold in through l2a_quality_flag.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pipeline/products/waveform_metrics.hpp"

namespace glaswave {

inline constexpr int kL2bProfileBins = 30;  // the real product's pai_z, pavd_z, cover_z
inline constexpr double kL2bDz_m = 5.0;

// The mission's constants, as every shot of a real L2B file carries them.
struct GediL2bSettings {
  double rhov = 0.6;   // canopy reflectance assumed
  double rhog = 0.4;   // ground reflectance assumed
  double rossg = 0.5;  // Ross G: projection of unit foliage area on the beam
  double omega = 1.0;  // clumping index
};

// One shot: its waveform (L1B's rxwaveform, bins in time order, bin 0 the highest) and where it
// lies, its noise mean, and L2A's selected group's results (elevations, metres).
struct GediL2bInput {
  std::span<const double> waveform;
  WaveformAxis axis;
  double noise_mean = 0.0;            // in the waveform's unit
  double elev_highestreturn_m = 0.0;  // signal begin (toploc)
  double elev_lowestmode_m = 0.0;     // the ground
  double elev_lowestreturn_m = 0.0;   // signal end (botloc)
  double zenith_rad = 0.0;            // the beam's angle from the local vertical
  bool l2a_quality_flag = true;
};

struct GediL2bResult {
  std::uint8_t algorithmrun_flag = 0;
  std::uint8_t l2b_quality_flag = 0;
  double rv = 0.0, rg = 0.0;  // canopy and ground integrals, waveform unit x bins
  double rhov = 0.0, rhog = 0.0, rossg = 0.0, omega = 0.0;
  double pgap_theta = 0.0;
  double cover = 0.0;
  double pai = 0.0;
  double fhd_normal = 0.0;
  // Pgap at each bin of the waveform: 1 above the signal's begin, pgap_theta at and below the
  // ground (L2B's pgap_theta_z over the waveform's bins).
  std::vector<double> pgap_theta_z;
  std::array<double, kL2bProfileBins> cover_z{}, pai_z{}, pavd_z{};

  // NaN everywhere, flags 0: the algorithm could not run.
  static GediL2bResult none(const GediL2bSettings& settings);
};

GediL2bResult gedi_l2b(const GediL2bInput& input, const GediL2bSettings& settings = {});

// The L2B input from L2A's result for the same waveform (L2aGroupResult's elevations), so that
// `glaswave retrieve` chains the two as the mission does.
struct L2aGroupResult;
GediL2bInput l2b_input(std::span<const double> waveform, const WaveformAxis& axis,
                       double noise_mean, const L2aGroupResult& l2a, double zenith_rad);

}  // namespace glaswave
