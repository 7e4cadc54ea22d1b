// Crowns: envelopes of turbid foliage (the seed's section 2.1), in a shot's local frame, and
// where a ray crosses them.
#pragma once

#include <optional>
#include <utility>

#include "canopy/canopy_settings.hpp"
#include "terrain/local_frame.hpp"

namespace glaswave {

struct Crown {
  CrownShape shape = CrownShape::ellipsoid;  // ellipsoid or cone
  Vec3 base_m{};                             // centre of the crown's bottom, local frame
  double radius_m = 0.0;                     // horizontal radius (a cone's at its base)
  double half_height_m = 0.0;                // the crown is 2 * half_height_m tall
  double area_density_m2_m3 = 0.0;           // one-sided plant area per unit volume
  int material = 0;                          // which foliage (stand) it is made of
};

// Volume of a crown's envelope (m^3).
double crown_volume_m3(CrownShape shape, double radius_m, double half_height_m);

// The parameter interval [t_in, t_out] where origin + t * direction is inside the crown, or
// nothing when the line misses it. t_in may be negative when the origin is inside.
std::optional<std::pair<double, double>> crown_interval(const Crown& crown, const Vec3& origin,
                                                        const Vec3& direction);

// A crown made ready for the many crossings of a shot: what crown_interval derives from the
// crown's shape (an ellipsoid's centre and inverse semi-axes, a cone's apex and slope) computed
// once. interval() is crown_interval.
class CrownCrossing {
 public:
  explicit CrownCrossing(const Crown& crown);
  std::optional<std::pair<double, double>> interval(const Vec3& origin,
                                                    const Vec3& direction) const;

 private:
  bool cone_;
  Vec3 centre_;            // an ellipsoid's centre, a cone's apex
  Vec3 inverse_axes_{};    // ellipsoid: 1 / semi-axes
  double slope_sq_ = 0.0;  // cone: (radius / height)^2
  double base_z_ = 0.0;    // cone: height of the base
};

}  // namespace glaswave
