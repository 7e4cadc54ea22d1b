// Canopy indices that need only a partition of the return into canopy and ground: the seed's
// waveform index WI = (CR - GR) / (CR + GR) (its eq. 3, section 3.3: CR and GR are the canopy and
// ground returns, the waveform's energy split by position in the waveform) and ICESat-2's
// photon-ratio canopy cover from ATL08's classified photons, plain and corrected for the ratio of
// canopy to ground reflectance. Pure functions of counts and energies, for `glaswave retrieve`.
#pragma once

#include <cstdint>
#include <span>

namespace glaswave {

// WI = (CR - GR) / (CR + GR), in [-1, 1] for non-negative returns: -1 bare ground, 1 no ground
// seen. NaN when CR + GR is not positive or either is not finite. The unit of CR and GR is
// theirs (J, counts x bins): the index is a ratio, insensitive to the absolute calibration.
double waveform_index(double canopy_return, double ground_return);

// The energy of a waveform (noise mean removed) on either side of a split, by position: CR from
// the signal's begin down to the split, GR from the split down to its end (fractional bins, bin 0
// the earliest and highest; each bin's value spread evenly over the bin). In the waveform's unit
// times bins.
struct CanopyGroundReturns {
  double canopy = 0.0, ground = 0.0;
};
CanopyGroundReturns split_returns(std::span<const double> waveform, double noise_mean,
                                  double begin_bin, double split_bin, double end_bin);

// Signal photons of a segment (or a shot) by ATL08's class (classed_pc_flag): 1 ground, 2
// canopy, 3 top of canopy; 0 (noise) is not signal.
struct PhotonClassCounts {
  std::int64_t ground = 0, canopy = 0, top_of_canopy = 0;
};
PhotonClassCounts count_photon_classes(std::span<const std::uint8_t> classed_pc_flag);

// Canopy cover from photon counts. `photon_ratio`: canopy photons (canopy and top of canopy) over
// all signal photons, Nc / (Nc + Ng), the ratio ICESat2VegR and ATL08's users compute, which
// assumes canopy and ground reflect alike. `reflectance_corrected`: Nc / (Nc + (rhov / rhog) Ng),
// the same correction as GEDI L2B's (a canopy of cover C returns in proportion to rhov C, the
// ground to rhog (1 - C)). NaN without signal photons; rhov_rhog must be positive.
struct PhotonCover {
  double photon_ratio = 0.0;
  double reflectance_corrected = 0.0;
};
PhotonCover photon_ratio_cover(const PhotonClassCounts& counts, double rhov_rhog);

}  // namespace glaswave
