// The roughness field and the subdivision of a ground mesh under the beam.
#include "terrain/roughness.hpp"

#include <Eigen/Dense>
#include <GeographicLib/UTMUPS.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "core/bit_mix.hpp"

namespace glaswave {
namespace {

constexpr auto mix = mix_bits;

// Standard normal white noise at a lattice node, a pure function of its arguments.
double white_noise(std::uint64_t zone_key, std::int64_t i, std::int64_t j) {
  const std::uint64_t h = mix(zone_key ^ mix(static_cast<std::uint64_t>(i) * 0xd1b54a32d192ed03ULL ^
                                             mix(static_cast<std::uint64_t>(j))));
  const double u1 = (static_cast<double>(h >> 11) + 0.5) * 0x1.0p-53;  // (0, 1)
  const double u2 = static_cast<double>(mix(h) >> 11) * 0x1.0p-53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);  // Box-Muller
}

// A position on the lattice's map: easting and northing (m) in a fixed zone, northings running
// on through the equator so that a zone's lattice has no seam there.
struct GridPoint {
  double x_m = 0.0, y_m = 0.0;
};

struct Zone {
  int number = 0;  // UTM 1..60, or 0 for UPS
  bool north = true;
  std::uint64_t key(std::uint64_t seed) const {
    return mix(seed ^ mix(static_cast<std::uint64_t>(
                          number == GeographicLib::UTMUPS::UPS ? (north ? 61 : 62) : number)));
  }
};

Zone zone_of(double lat_deg, double lon_deg) {
  return {GeographicLib::UTMUPS::StandardZone(lat_deg, lon_deg), lat_deg >= 0.0};
}

GridPoint grid_point(const Zone& zone, double lat_deg, double lon_deg) {
  int zone_number = 0;
  bool north = true;
  double x = 0, y = 0, gamma = 0, k = 0;
  GeographicLib::UTMUPS::Forward(lat_deg, lon_deg, zone_number, north, x, y, gamma, k, zone.number);
  if (zone.number != GeographicLib::UTMUPS::UPS && !north)
    y -= 1.0e7;  // UTM south's false northing
  return {x, y};
}

// A quadratic map between two planes, fitted by least squares; over a shot's patch the map
// between the UTM grid and the local frame departs from affine by well under a millimetre.
class QuadraticMap {
 public:
  QuadraticMap(const std::vector<std::array<double, 2>>& from,
               const std::vector<std::array<double, 2>>& to, double length_m)
      : inverse_length_(1.0 / length_m) {
    Eigen::MatrixXd basis(from.size(), 6);
    Eigen::MatrixXd target(to.size(), 2);
    for (std::size_t n = 0; n < from.size(); ++n) {
      basis.row(n) = row(from[n][0], from[n][1]);
      target.row(n) << to[n][0], to[n][1];
    }
    coefficients_ = basis.colPivHouseholderQr().solve(target);
  }
  std::array<double, 2> operator()(double u, double v) const {
    const Eigen::RowVector2d mapped = row(u, v) * coefficients_;
    return {mapped(0), mapped(1)};
  }

 private:
  Eigen::Matrix<double, 1, 6> row(double u, double v) const {
    const double s = u * inverse_length_, t = v * inverse_length_;
    Eigen::Matrix<double, 1, 6> r;
    r << 1.0, s, t, s * s, s * t, t * t;
    return r;
  }
  double inverse_length_;
  Eigen::Matrix<double, 6, 2> coefficients_;
};

// The base mesh as a height field: which triangle lies over a point, and its height there.
class HeightIndex {
 public:
  explicit HeightIndex(const GroundMesh& mesh) : mesh_(mesh) {
    const std::size_t count = mesh.triangles.size() / 3;
    double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
    for (std::uint32_t v : mesh.triangles) {
      x0 = std::min<double>(x0, mesh.vertices_m[3 * v]);
      x1 = std::max<double>(x1, mesh.vertices_m[3 * v]);
      y0 = std::min<double>(y0, mesh.vertices_m[3 * v + 1]);
      y1 = std::max<double>(y1, mesh.vertices_m[3 * v + 1]);
    }
    x0_ = x0;
    y0_ = y0;
    // Buckets about the size of a triangle.
    const double area_m2 = std::max((x1 - x0) * (y1 - y0), 1e-6);
    cell_m_ = std::max(std::sqrt(2.0 * area_m2 / std::max<std::size_t>(count, 1)), 1e-3);
    nx_ = std::clamp(static_cast<int>((x1 - x0) / cell_m_) + 1, 1, 2048);
    ny_ = std::clamp(static_cast<int>((y1 - y0) / cell_m_) + 1, 1, 2048);
    cell_m_ = std::max((x1 - x0) / nx_, (y1 - y0) / ny_) * (1.0 + 1e-9) + 1e-9;
    start_.assign(static_cast<std::size_t>(nx_) * ny_ + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<std::uint32_t> fill = pass ? start_ : std::vector<std::uint32_t>();
      if (pass) entries_.resize(start_.back());
      for (std::size_t t = 0; t < count; ++t) {
        int bx0, bx1, by0, by1;
        bounds(t, bx0, bx1, by0, by1);
        for (int by = by0; by <= by1; ++by) {
          for (int bx = bx0; bx <= bx1; ++bx) {
            const std::size_t bucket = static_cast<std::size_t>(by) * nx_ + bx;
            if (pass)
              entries_[fill[bucket]++] = static_cast<std::uint32_t>(t);
            else
              ++start_[bucket + 1];
          }
        }
      }
      if (!pass)
        for (std::size_t b = 1; b < start_.size(); ++b) start_[b] += start_[b - 1];
    }
  }

  std::optional<double> height_m(double x, double y) const {
    const int bx = static_cast<int>(std::floor((x - x0_) / cell_m_));
    const int by = static_cast<int>(std::floor((y - y0_) / cell_m_));
    if (bx < 0 || by < 0 || bx >= nx_ || by >= ny_) return std::nullopt;
    const std::size_t bucket = static_cast<std::size_t>(by) * nx_ + bx;
    for (std::uint32_t e = start_[bucket]; e < start_[bucket + 1]; ++e) {
      const std::uint32_t* v = &mesh_.triangles[3 * entries_[e]];
      const double ax = mesh_.vertices_m[3 * v[0]], ay = mesh_.vertices_m[3 * v[0] + 1];
      const double bx_ = mesh_.vertices_m[3 * v[1]], by_ = mesh_.vertices_m[3 * v[1] + 1];
      const double cx = mesh_.vertices_m[3 * v[2]], cy = mesh_.vertices_m[3 * v[2] + 1];
      const double d = (by_ - cy) * (ax - cx) + (cx - bx_) * (ay - cy);
      if (d == 0.0) continue;
      const double l0 = ((by_ - cy) * (x - cx) + (cx - bx_) * (y - cy)) / d;
      const double l1 = ((cy - ay) * (x - cx) + (ax - cx) * (y - cy)) / d;
      const double l2 = 1.0 - l0 - l1;
      constexpr double slack = -1e-9;
      if (l0 < slack || l1 < slack || l2 < slack) continue;
      return l0 * mesh_.vertices_m[3 * v[0] + 2] + l1 * mesh_.vertices_m[3 * v[1] + 2] +
             l2 * mesh_.vertices_m[3 * v[2] + 2];
    }
    return std::nullopt;
  }

 private:
  void bounds(std::size_t t, int& bx0, int& bx1, int& by0, int& by1) const {
    double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh_.triangles[3 * t + k];
      x0 = std::min<double>(x0, mesh_.vertices_m[3 * v]);
      x1 = std::max<double>(x1, mesh_.vertices_m[3 * v]);
      y0 = std::min<double>(y0, mesh_.vertices_m[3 * v + 1]);
      y1 = std::max<double>(y1, mesh_.vertices_m[3 * v + 1]);
    }
    bx0 = std::clamp(static_cast<int>(std::floor((x0 - x0_) / cell_m_)), 0, nx_ - 1);
    bx1 = std::clamp(static_cast<int>(std::floor((x1 - x0_) / cell_m_)), 0, nx_ - 1);
    by0 = std::clamp(static_cast<int>(std::floor((y0 - y0_) / cell_m_)), 0, ny_ - 1);
    by1 = std::clamp(static_cast<int>(std::floor((y1 - y0_) / cell_m_)), 0, ny_ - 1);
  }

  const GroundMesh& mesh_;
  double x0_ = 0.0, y0_ = 0.0, cell_m_ = 1.0;
  int nx_ = 1, ny_ = 1;
  std::vector<std::uint32_t> start_, entries_;  // triangles of each bucket (CSR)
};

struct ClipVertex {
  double x, y, z;
};

// Sutherland-Hodgman: the part of a convex polygon where side(p) >= 0, side being affine.
template <typename Side>
std::vector<ClipVertex> clip(const std::vector<ClipVertex>& polygon, Side side) {
  std::vector<ClipVertex> out;
  for (std::size_t k = 0; k < polygon.size(); ++k) {
    const ClipVertex& p = polygon[k];
    const ClipVertex& q = polygon[(k + 1) % polygon.size()];
    const double sp = side(p), sq = side(q);
    if (sp >= 0.0) out.push_back(p);
    if ((sp >= 0.0) != (sq >= 0.0)) {
      const double t = sp / (sp - sq);
      out.push_back({p.x + t * (q.x - p.x), p.y + t * (q.y - p.y), p.z + t * (q.z - p.z)});
    }
  }
  return out;
}

}  // namespace

RoughnessField::RoughnessField(const RoughnessSettings& settings, std::uint64_t seed)
    : rms_m_(settings.rms_m),
      correlation_m_(settings.correlation_m),
      spacing_m_(settings.correlation_m / 3.0),
      seed_(seed) {
  if (!enabled()) return;
  // Noise smoothed by exp(-2 r^2 / L^2) has covariance exp(-r^2 / L^2); taps down to 1e-4.
  const int half_taps =
      static_cast<int>(std::ceil(std::sqrt(std::log(1e4) / 2.0) * correlation_m_ / spacing_m_));
  for (int k = -half_taps; k <= half_taps; ++k) {
    const double r_m = k * spacing_m_;
    kernel_.push_back(std::exp(-2.0 * r_m * r_m / (correlation_m_ * correlation_m_)));
  }
  // Covariance of smoothed nodes d apart along one axis: A(d) = sum_k a_k a_(k+d); in 2-D it is
  // A(di) A(dj). Over a lattice triangle the linear surface through nodes f_a has mean variance
  // sum_ab E[l_a l_b] C_ab, with E[l_a^2] = 1/6 and E[l_a l_b] = 1/12 for uniform barycentric
  // coordinates l: var(node) * (1/2 + (rho_10 + rho_01 + rho_11) / 6).
  double a0 = 0.0, a1 = 0.0;
  for (std::size_t k = 0; k < kernel_.size(); ++k) {
    a0 += kernel_[k] * kernel_[k];
    if (k + 1 < kernel_.size()) a1 += kernel_[k] * kernel_[k + 1];
  }
  const double rho = a1 / a0;
  const double surface_variance = a0 * a0 * (0.5 + (2.0 * rho + rho * rho) / 6.0);
  scale_ = rms_m_ / std::sqrt(surface_variance);
}

double RoughnessField::height_m(double lat_deg, double lon_deg) const {
  if (!enabled()) return 0.0;
  const Zone zone = zone_of(lat_deg, lon_deg);
  const GridPoint p = grid_point(zone, lat_deg, lon_deg);
  const double u = p.x_m / spacing_m_, v = p.y_m / spacing_m_;
  const auto i = static_cast<std::int64_t>(std::floor(u)),
             j = static_cast<std::int64_t>(std::floor(v));
  const double fu = u - i, fv = v - j;
  // The four nodes of the cell from one window of noise, smoothed along each axis in turn.
  const std::uint64_t key = zone.key(seed_);
  const int half_taps = static_cast<int>(kernel_.size() / 2), side = 2 * half_taps + 2;
  std::vector<double> rows(2 * static_cast<std::size_t>(side), 0.0);  // [node column][noise row]
  for (int l = 0; l < side; ++l)
    for (int k = 0; k < side; ++k) {
      const double w = white_noise(key, i - half_taps + k, j - half_taps + l);
      if (k < side - 1) rows[l] += kernel_[k] * w;
      if (k > 0) rows[side + l] += kernel_[k - 1] * w;
    }
  double node[2][2] = {};  // [row offset][column offset]
  for (int di = 0; di < 2; ++di)
    for (int l = 0; l < side; ++l) {
      if (l < side - 1) node[0][di] += kernel_[l] * rows[di * side + l];
      if (l > 0) node[1][di] += kernel_[l - 1] * rows[di * side + l];
    }
  const double a = node[0][0], b = node[0][1], c = node[1][0], d = node[1][1];
  // The lattice triangle holding the point, as the mesh has it.
  const double value = fu >= fv ? a + fu * (b - a) + fv * (d - b) : a + fv * (c - a) + fu * (d - c);
  return scale_ * value;
}

GroundMesh RoughnessField::roughen(const GroundMesh& base, const LocalFrame& frame,
                                   double half_size_m, double base_spacing_m) const {
  if (!enabled() || base.triangles.empty() || half_size_m <= 0.0) return base;
  const Geodetic& origin = frame.origin();
  const Zone zone = zone_of(origin.lat_deg, origin.lon_deg);
  const std::uint64_t key = zone.key(seed_);
  const double h = spacing_m_;

  // Maps between the lattice's grid and the frame, fitted on 5 x 5 points of the region at the
  // ground's mean height: the frame's axes are not the local verticals, so a point's height moves
  // its latitude and longitude, but by well under a millimetre within tens of metres of it.
  const double z_ref_m = 0.5 * (base.min_height_m + base.max_height_m);
  const GridPoint centre = grid_point(zone, origin.lat_deg, origin.lon_deg);
  std::vector<std::array<double, 2>> local_points, grid_points;
  for (int b = -2; b <= 2; ++b) {
    for (int a = -2; a <= 2; ++a) {
      const double x = 0.5 * a * half_size_m, y = 0.5 * b * half_size_m;
      const Geodetic g = frame.to_geodetic({x, y, z_ref_m});
      const GridPoint p = grid_point(zone, g.lat_deg, g.lon_deg);
      local_points.push_back({x, y});
      grid_points.push_back({p.x_m - centre.x_m, p.y_m - centre.y_m});
    }
  }
  const QuadraticMap to_local(grid_points, local_points, half_size_m);
  const QuadraticMap to_grid(local_points, grid_points, half_size_m);

  // The lattice nodes covering the square, shrunk about the origin when they are too many.
  std::int64_t i0 = 0, i1 = 0, j0 = 0, j1 = 0;
  for (double shrink = 1.0;; shrink *= 0.95) {
    const double r_m = half_size_m * shrink;
    double gx0 = std::numeric_limits<double>::infinity(), gy0 = gx0, gx1 = -gx0, gy1 = -gx0;
    for (const auto& [x, y] :
         {std::array<double, 2>{-r_m, -r_m}, {r_m, -r_m}, {r_m, r_m}, {-r_m, r_m}}) {
      const auto g = to_grid(x, y);
      gx0 = std::min(gx0, g[0] + centre.x_m);
      gx1 = std::max(gx1, g[0] + centre.x_m);
      gy0 = std::min(gy0, g[1] + centre.y_m);
      gy1 = std::max(gy1, g[1] + centre.y_m);
    }
    i0 = static_cast<std::int64_t>(std::floor(gx0 / h));
    i1 = static_cast<std::int64_t>(std::ceil(gx1 / h));
    j0 = static_cast<std::int64_t>(std::floor(gy0 / h));
    j1 = static_cast<std::int64_t>(std::ceil(gy1 / h));
    if ((i1 - i0 + 1) * (j1 - j0 + 1) <= max_nodes) break;
  }
  const int ni = static_cast<int>(i1 - i0 + 1), nj = static_cast<int>(j1 - j0 + 1);

  // Smoothed noise of every node: white noise with a margin of half the kernel, convolved along
  // each axis in turn.
  const int half_taps = static_cast<int>(kernel_.size() / 2);
  const int wi = ni + 2 * half_taps, wj = nj + 2 * half_taps;
  std::vector<double> noise(static_cast<std::size_t>(wi) * wj);
  for (int j = 0; j < wj; ++j)
    for (int i = 0; i < wi; ++i)
      noise[static_cast<std::size_t>(j) * wi + i] =
          white_noise(key, i0 - half_taps + i, j0 - half_taps + j);
  std::vector<double> along_i(static_cast<std::size_t>(ni) * wj, 0.0);
  for (int j = 0; j < wj; ++j)
    for (int i = 0; i < ni; ++i) {
      double sum = 0.0;
      for (std::size_t k = 0; k < kernel_.size(); ++k)
        sum += kernel_[k] * noise[static_cast<std::size_t>(j) * wi + i + k];
      along_i[static_cast<std::size_t>(j) * ni + i] = sum;
    }
  std::vector<double> relief_m(static_cast<std::size_t>(ni) * nj, 0.0);
  const int ramp_nodes = std::max(1, static_cast<int>(std::lround(2.0 * correlation_m_ / h)));
  for (int j = 0; j < nj; ++j)
    for (int i = 0; i < ni; ++i) {
      double sum = 0.0;
      for (std::size_t k = 0; k < kernel_.size(); ++k)
        sum += kernel_[k] * along_i[(j + k) * ni + i];
      const int edge = std::min({i, ni - 1 - i, j, nj - 1 - j});
      const double taper = std::min(1.0, static_cast<double>(edge) / ramp_nodes);
      relief_m[static_cast<std::size_t>(j) * ni + i] = scale_ * taper * sum;
    }

  GroundMesh mesh;
  mesh.vertices_m = base.vertices_m;
  const HeightIndex ground(base);
  auto add_vertex = [&](double x, double y, double z) {
    mesh.vertices_m.insert(mesh.vertices_m.end(),
                           {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
    return static_cast<std::uint32_t>(mesh.vertices_m.size() / 3 - 1);
  };

  // The mesh's nodes on the base surface, raised by the relief: the lattice's nodes, or r times
  // finer where the base has finer detail (a DEM of fine cells) so that its own relief stays.
  // The field varies over a correlation length, three lattice steps: between nodes it is
  // interpolated bilinearly. At most 1024 nodes a side: finer detail is then smoothed.
  int r = 1;
  if (base_spacing_m < h) r = static_cast<int>(std::ceil(h / base_spacing_m - 1e-9));
  r = std::clamp(r, 1, std::max(1, 1023 / std::max(1, std::max(ni, nj) - 1)));
  const int fi = (ni - 1) * r + 1, fj = (nj - 1) * r + 1;
  auto relief_at = [&](int a, int b) {  // fine node (a, b): lattice (a / r, b / r)
    const int i = std::min(a / r, ni - 2 < 0 ? 0 : ni - 2),
              j = std::min(b / r, nj - 2 < 0 ? 0 : nj - 2);
    const double u = static_cast<double>(a - i * r) / r, v = static_cast<double>(b - j * r) / r;
    auto at = [&](int ii, int jj) {
      return relief_m[static_cast<std::size_t>(std::min(jj, nj - 1)) * ni + std::min(ii, ni - 1)];
    };
    return (1 - u) * (1 - v) * at(i, j) + u * (1 - v) * at(i + 1, j) + (1 - u) * v * at(i, j + 1) +
           u * v * at(i + 1, j + 1);
  };
  constexpr std::uint32_t missing = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> node_vertex(static_cast<std::size_t>(fi) * fj, missing);
  for (int b = 0; b < fj; ++b)
    for (int a = 0; a < fi; ++a) {
      const auto [x, y] = to_local((i0 + static_cast<double>(a) / r) * h - centre.x_m,
                                   (j0 + static_cast<double>(b) / r) * h - centre.y_m);
      if (const auto z = ground.height_m(x, y))
        node_vertex[static_cast<std::size_t>(b) * fi + a] = add_vertex(x, y, *z + relief_at(a, b));
    }
  for (int b = 0; b + 1 < fj; ++b)
    for (int a = 0; a + 1 < fi; ++a) {
      const std::uint32_t p = node_vertex[static_cast<std::size_t>(b) * fi + a],
                          q = node_vertex[static_cast<std::size_t>(b) * fi + a + 1];
      const std::uint32_t c = node_vertex[static_cast<std::size_t>(b + 1) * fi + a],
                          d = node_vertex[static_cast<std::size_t>(b + 1) * fi + a + 1];
      if (p != missing && q != missing && d != missing)
        mesh.triangles.insert(mesh.triangles.end(), {p, q, d});
      if (p != missing && d != missing && c != missing)
        mesh.triangles.insert(mesh.triangles.end(), {p, d, c});
    }

  // The base outside the lattice's region: its outline in the frame is a convex quadrilateral
  // (counter-clockwise, as east and north are in both). A triangle that crosses it is cut along
  // it; the outside is split into four convex parts (outside edge k, inside the edges before).
  std::array<std::array<double, 2>, 4> quad;
  {
    const std::array<std::array<std::int64_t, 2>, 4> corners = {
        {{i0, j0}, {i1, j0}, {i1, j1}, {i0, j1}}};
    for (int k = 0; k < 4; ++k)
      quad[k] = to_local(corners[k][0] * h - centre.x_m, corners[k][1] * h - centre.y_m);
  }
  auto side = [&](int edge, double x, double y) {
    const auto& p = quad[edge];
    const auto& q = quad[(edge + 1) % 4];
    return (q[0] - p[0]) * (y - p[1]) - (q[1] - p[1]) * (x - p[0]);  // > 0 inside
  };
  for (std::size_t t = 0; t < base.triangles.size(); t += 3) {
    std::vector<ClipVertex> triangle;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = base.triangles[t + k];
      triangle.push_back(
          {base.vertices_m[3 * v], base.vertices_m[3 * v + 1], base.vertices_m[3 * v + 2]});
    }
    bool disjoint = false, inside = true;
    for (int edge = 0; edge < 4; ++edge) {
      int outside = 0;
      for (const ClipVertex& p : triangle) outside += side(edge, p.x, p.y) < 0.0 ? 1 : 0;
      disjoint = disjoint || outside == 3;
      inside = inside && outside == 0;
    }
    if (disjoint) {
      mesh.triangles.insert(mesh.triangles.end(), base.triangles.begin() + t,
                            base.triangles.begin() + t + 3);
      continue;
    }
    if (inside) continue;
    for (int edge = 0; edge < 4; ++edge) {
      std::vector<ClipVertex> part =
          clip(triangle, [&](const ClipVertex& p) { return -side(edge, p.x, p.y); });
      for (int before = 0; before < edge && part.size() >= 3; ++before)
        part = clip(part, [&](const ClipVertex& p) { return side(before, p.x, p.y); });
      if (part.size() < 3) continue;
      double twice_area = 0.0;
      for (std::size_t k = 0; k < part.size(); ++k) {
        const ClipVertex& p = part[k];
        const ClipVertex& q = part[(k + 1) % part.size()];
        twice_area += p.x * q.y - q.x * p.y;
      }
      if (std::abs(twice_area) < 1e-8) continue;  // a sliver along an edge
      const std::uint32_t first = add_vertex(part[0].x, part[0].y, part[0].z);
      std::uint32_t previous = add_vertex(part[1].x, part[1].y, part[1].z);
      for (std::size_t k = 2; k < part.size(); ++k) {
        const std::uint32_t next = add_vertex(part[k].x, part[k].y, part[k].z);
        mesh.triangles.insert(mesh.triangles.end(), {first, previous, next});
        previous = next;
      }
    }
  }

  mesh.min_height_m = std::numeric_limits<double>::infinity();
  mesh.max_height_m = -std::numeric_limits<double>::infinity();
  for (std::uint32_t v : mesh.triangles) {
    mesh.min_height_m = std::min<double>(mesh.min_height_m, mesh.vertices_m[3 * v + 2]);
    mesh.max_height_m = std::max<double>(mesh.max_height_m, mesh.vertices_m[3 * v + 2]);
  }
  if (mesh.triangles.empty()) mesh.min_height_m = mesh.max_height_m = 0.0;
  return mesh;
}

}  // namespace glaswave
