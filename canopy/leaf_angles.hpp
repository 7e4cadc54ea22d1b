// Leaf angle distributions (the seed's LAD): the inclination density g(theta_L), the
// projection function G(Omega) (mean projected leaf area per unit leaf area, Ross), and leaf
// normals drawn as a ray meets them: from g weighted by the projected area |n . Omega|.
#pragma once

#include <array>
#include <cmath>
#include <vector>

#include "canopy/canopy_settings.hpp"
#include "core/turn_trig.hpp"
#include "terrain/local_frame.hpp"

namespace glaswave {

class LeafAngles {
 public:
  // `mean_deg` is used by the ellipsoidal (Campbell) distribution only. Leaves have uniform
  // azimuths, so G depends on the zenith of the direction alone.
  LeafAngles(LeafAngleDistribution distribution, double mean_deg);

  // g(theta_L), normalised so that its integral over [0, pi/2] is 1.
  double density(double inclination_rad) const;

  // G for a direction whose cosine with the vertical is `cos_zenith` (sign ignored).
  double projection(double cos_zenith) const;

  // A leaf normal (upper hemisphere) met by a ray travelling along `direction`: drawn from the
  // distribution weighted by |n . direction| (a ray meets leaves in proportion to the area they
  // present to it).
  template <class Uniform>
  Vec3 sample_normal(const Vec3& direction, Uniform&& uniform) const {
    for (;;) {
      const double u1 = uniform(), u2 = uniform(), u3 = uniform();
      const Vec3 normal = normal_at(u1, u2);
      if (u3 < std::abs(dot(normal, direction))) return normal;
    }
  }

 private:
  Vec3 normal_at(double u_inclination, double u_azimuth) const;

  LeafAngleDistribution distribution_;
  double campbell_chi_ = 1.0;
  std::vector<double> inclination_cdf_;    // on a uniform grid of inclinations over [0, pi/2]
  std::vector<double> projection_table_;   // G on a uniform grid of |cos zenith| over [0, 1]
  std::vector<int> inclination_guide_;     // first CDF entry above j / guide_steps, for each j
  std::vector<SinCos> inclination_nodes_;  // sin and cos of the CDF grid's inclinations
};

}  // namespace glaswave

namespace glaswave {

// A bi-Lambertian element (a leaf; bark with transmittance 0) of normal `normal`, lit by light
// travelling along `incoming` and seen along `outgoing` (travel directions): the element's
// reflectance if the light leaves on the side it came from, else its transmittance, times the
// area it presents to the light. Averaged over normals drawn with LeafAngles::sample_normal
// for `outgoing` (reversed), it is Gamma(incoming -> outgoing) / G(outgoing): the area
// scattering phase function of Ross, times pi, over the projection function.
inline double bilambertian_response(const Vec3& normal, const Vec3& incoming, const Vec3& outgoing,
                                    double reflectance, double transmittance) {
  const double in = dot(normal, incoming), out = dot(normal, outgoing);
  return (in * out < 0.0 ? reflectance : transmittance) * std::abs(in);
}

}  // namespace glaswave
