// The ATL03- and ATL08-like granules as a product writer: it keeps each record's photons and
// footprint as they come (in any order), and at the end classifies each beam's photons and writes
// DIR/atl03.h5 and DIR/atl08.h5 (icesat2_products.hpp). The background rate ATL03 reports and
// ATL08's noise filter uses is estimated from the photons, as ATLAS's processing does. A record's
// photons are in its own time order; the records go in shot order, so the products are the same for
// any thread count, split, MPI or resume.
#pragma once

#include <filesystem>
#include <map>
#include <string>

#include "pipeline/products/icesat2_products.hpp"
#include "pipeline/products/product_writer.hpp"

namespace glaswave {

class Icesat2Writer : public ProductWriter {
 public:
  Icesat2Writer(const std::filesystem::path& out_dir, const Icesat2ProductSettings& settings,
                const RunInfo& info);

  void write(std::int64_t index, const ShotRecord& shot) override;
  void finish(const RunStats& stats) override;
  void abort() noexcept override;

 private:
  struct Kept {
    std::uint8_t beam = 0;  // ShotRecord::beam
    BeamShot shot;
    std::vector<BeamPhoton> photons;
    double below_ground = 0;  // its photons in the range window's lowest fifth
  };

  // Each shot's background rate, as ATL03 estimates it from the photons outside the surface:
  // those in the lowest fifth of the range window (15 m or more below the ground at the
  // footprint centre), over the shots within 500 of it.
  void estimate_background(std::vector<BeamShot>& shots, const std::vector<double>& below) const;
  // The beam's shots and photons from the kept records that belong to it, in record order.
  BeamTrack gather_beam(const GranuleBeam& granule_beam) const;

  std::filesystem::path out_dir_;
  Icesat2ProductSettings settings_;
  GranuleInfo info_;
  std::int64_t shots_ = 0;
  double window_start_ns_ = 0.0, window_ns_ = 0.0;  // the range window, bins' clock
  std::map<std::int64_t, Kept> kept_;
  bool done_ = false;
};

}  // namespace glaswave
