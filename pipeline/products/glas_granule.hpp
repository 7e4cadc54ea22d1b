// GLAS GLAH01- and GLAH14-style granules (PRODUCT.md section 10): DIR/glah01.h5 and
// DIR/glah14.h5 under Data_40HZ/ at the paths of NSIDC's GLAH01 and GLAH14 (release 34) HDF5
// files, as SpaceLiDAR.jl's GLAH14 reader and NSIDC's iceflow read them. Shots are identified by
// (i_rec_ndx, i_shot_count): a granule track's come through unchanged (its shot number is
// i_rec_ndx * 40 + i_shot_count - 1), a synthetic track's shot k is record k / 40, shot
// k % 40 + 1. Heights are on WGS84, or on GLAS's TOPEX/Poseidon ellipsoid with
// output.glas_ellipsoid "topex"; Geophysical/d_deltaEllip is WGS84 less T/P height either way.
// The simulation's truth is in Data_40HZ/glaswave_truth. docs/granules.md lists every path.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include "pipeline/products/hdf5_granule_writer.hpp"
#include "pipeline/products/icesat2_products.hpp"

namespace glaswave {

enum class GlasLevel : std::uint8_t { glah01, glah14 };

// GLAS's fill for a double that has no value (its HDF5 files' _FillValue).
inline constexpr double kGlasFill = 1.7976931348623157e308;

// The TOPEX/Poseidon ellipsoid GLAS heights are on: a = 6378136.3 m, 1/f = 298.257.
// WGS84 height less T/P height of the point at WGS84 (lat, lon, h): about -0.7 m at the equator.
double glas_delta_ellipsoid_m(double lat_deg, double lon_deg, double h_m);

class GlasGranuleWriter : public Hdf5GranuleWriter {
 public:
  // Writes the band nearest 1064 nm (GLAS's waveforms are its 1064 nm channel's).
  // `cloud_layers`: GLAH14's elv_cloud_flg, 1 with any (ProductSettings::glas_cloud_layers).
  GlasGranuleWriter(const std::filesystem::path& final_path, GlasLevel level, bool topex,
                    const RunInfo& info,
                    std::optional<std::vector<CloudLayer>> cloud_layers = std::nullopt);

 private:
  struct Shot {
    std::int32_t record = 0;
    std::int16_t count = 1;
    std::int32_t peaks = 0;
    double time = 0, lat = 0, lon = 0, elev = 0, dem = 0, delta_ellip = 0, reflectance_uc = 0;
    double begin_off = 0, end_off = 0;
    double amp[6], area[6], sigma[6], center_off[6];
    double cover = 0, pai = 0, height = 0, pgap = 0;
    std::vector<float> rx, rx_canopy, rx_ground;
    // What the missions' readers open besides (docs/granules.md): the range to the last gate
    // and the land range's offset from it, the waveform's skewness and smoothed peaks, its
    // noise (counts), the last gate's time on a 1 GHz clock from the transmit peak's address.
    double ref_range = 0, land_off = 0, skew = 0, noise_mean = 0, noise_sd = 0;
    std::int32_t peaks1 = 0, resp_end = 0;
    bool saturated = false;
  };
  void keep(std::int64_t index, const ShotRecord& shot) override;
  void keep_reader_fields(Shot& s, const ShotRecord& r) const;
  void write_file(Hdf5Writer& file) override;

  GlasLevel level_;
  bool topex_;
  std::optional<std::vector<CloudLayer>> cloud_layers_;
  std::size_t band_;
  std::vector<Shot> shots_;
};

}  // namespace glaswave
