// Analytic terrains for the footprint tests: level ground over the whole Earth, steep folded
// hills whose rays cross the ground many times, and ground with data only inside a cap.
#pragma once

#include <GeographicLib/Geodesic.hpp>
#include <GeographicLib/LocalCartesian.hpp>
#include <cmath>
#include <limits>
#include <numbers>

#include "terrain/terrain.hpp"

namespace glaswave::testing {

// Ground at one height above WGS84 everywhere.
class LevelTerrain final : public Terrain {
 public:
  explicit LevelTerrain(double height_m = 0.0) : height_m_(height_m) {}
  double height_m(double, double) const override { return height_m_; }
  double detail_m() const override { return 1.0e9; }

 private:
  double height_m_;
};

// Ridges and a dome in the tangent plane of an origin: heights 200..2800 m, slopes up to about
// 76 degrees, so that slanted rays pass over several crests before they land.
class SteepHills final : public Terrain {
 public:
  SteepHills(double lat_deg, double lon_deg) : frame_(lat_deg, lon_deg, 0.0) {}
  double height_m(double lat_deg, double lon_deg) const override {
    double e = 0, n = 0, u = 0;
    frame_.Forward(lat_deg, lon_deg, 0.0, e, n, u);
    return height_at(e, n);
  }
  double detail_m() const override { return 10.0; }
  static double height_at(double east_m, double north_m) {
    constexpr double pi = std::numbers::pi;
    const double ridges =
        1000.0 * std::sin(2 * pi * east_m / 2000.0) * std::cos(2 * pi * north_m / 2500.0);
    const double de = east_m - 300.0, dn = north_m + 200.0;
    const double dome = 600.0 * std::exp(-(de * de + dn * dn) / (2.0 * 400.0 * 400.0));
    return 1200.0 + ridges + dome;
  }
  static constexpr double max_height_m = 2800.0;
  const GeographicLib::LocalCartesian& frame() const { return frame_; }

 private:
  GeographicLib::LocalCartesian frame_;
};

// Level ground at `height_m` within `radius_m` (geodesic) of a centre, no data elsewhere: a DEM
// tile as the footprint locator sees it.
class CapTerrain final : public Terrain {
 public:
  CapTerrain(double lat_deg, double lon_deg, double radius_m, double height_m = 0.0)
      : lat_deg_(lat_deg), lon_deg_(lon_deg), radius_m_(radius_m), height_m_(height_m) {}
  double height_m(double lat_deg, double lon_deg) const override {
    double distance_m = 0;
    GeographicLib::Geodesic::WGS84().Inverse(lat_deg_, lon_deg_, lat_deg, lon_deg, distance_m);
    return distance_m <= radius_m_ ? height_m_ : std::numeric_limits<double>::quiet_NaN();
  }
  double detail_m() const override { return 100.0; }

 private:
  double lat_deg_, lon_deg_, radius_m_, height_m_;
};

}  // namespace glaswave::testing
