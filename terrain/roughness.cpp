// The roughness field and the subdivision of a ground mesh under the beam.
#include "terrain/roughness.hpp"

#include <Eigen/Dense>
#include <GeographicLib/UTMUPS.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "core/random.hpp"
#include "core/samplers.hpp"

namespace glaswave {
namespace {

// A position on the lattice's map: easting and northing (m) in a fixed zone, northings running
// on through the equator so that a zone's lattice has no seam there.
struct GridPoint {
  double x_m = 0.0, y_m = 0.0;
};

struct Zone {
  int number = 0;  // UTM 1..60, or 0 for UPS
  bool north = true;
  // The lattices of the zones: UTM's by number (northings run on through the equator), UPS's
  // two apart.
  std::uint64_t index() const {
    return static_cast<std::uint64_t>(number == GeographicLib::UTMUPS::UPS ? (north ? 61 : 62)
                                                                           : number);
  }
};

// Standard normal white noise at the lattice nodes, each a pure function of (seed, zone, level,
// node): node (i, j)'s stream is keyed by the node at the zone's ray. The coarser lattices
// (level > 0) have their own noise; the finest keeps the key it always had.
ShotStreams node_streams(std::uint64_t seed, const Zone& zone, int level) {
  return ShotStreams(seed, zone.index() + 64 * static_cast<std::uint64_t>(level),
                     RandomPurpose::roughness);
}

// The Gaussian-smoothed noise of the ni x nj lattice nodes from (i0, j0) (node (i0 + a, j0 + b)
// at b * ni + a): white noise with a margin of half the kernel, convolved along each axis in turn.
// Each sum runs over the taps in order (so its bits are fixed); the loops run along rows, where
// they vectorise.
std::vector<double> smoothed_noise(std::uint64_t seed, const Zone& zone, int level,
                                   const std::vector<double>& kernel, std::int64_t i0,
                                   std::int64_t j0, int ni, int nj) {
  const int half_taps = static_cast<int>(kernel.size() / 2);
  const int wi = ni + 2 * half_taps, wj = nj + 2 * half_taps;
  const ShotStreams streams = node_streams(seed, zone, level);
  std::vector<double> noise(static_cast<std::size_t>(wi) * wj);
  for (int j = 0; j < wj; ++j)
    for (int i = 0; i < wi; ++i) {
      RandomStream random = streams.at(pair_key(i0 - half_taps + i, j0 - half_taps + j));
      noise[static_cast<std::size_t>(j) * wi + i] = standard_normal(random);
    }
  std::vector<double> along_i(static_cast<std::size_t>(ni) * wj, 0.0);
  for (int j = 0; j < wj; ++j) {
    double* out = &along_i[static_cast<std::size_t>(j) * ni];
    for (std::size_t k = 0; k < kernel.size(); ++k) {
      const double tap = kernel[k];
      const double* in = &noise[static_cast<std::size_t>(j) * wi + k];
      for (int i = 0; i < ni; ++i) out[i] += tap * in[i];
    }
  }
  std::vector<double> smoothed(static_cast<std::size_t>(ni) * nj, 0.0);
  for (int j = 0; j < nj; ++j) {
    double* out = &smoothed[static_cast<std::size_t>(j) * ni];
    for (std::size_t k = 0; k < kernel.size(); ++k) {
      const double tap = kernel[k];
      const double* in = &along_i[(j + k) * ni];
      for (int i = 0; i < ni; ++i) out[i] += tap * in[i];
    }
  }
  return smoothed;
}

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

// The region of a roughened mesh on the lattice: the nodes [i0, i1] x [j0, j1] of the zone's
// lattice (spacing h), and the maps between the lattice's grid (relative to the frame's origin,
// `centre`) and the frame.
struct LatticeRegion {
  Zone zone;
  GridPoint centre;
  QuadraticMap to_local, to_grid;
  double h;
  std::int64_t i0 = 0, i1 = 0, j0 = 0, j1 = 0;

  int ni() const { return static_cast<int>(i1 - i0 + 1); }
  int nj() const { return static_cast<int>(j1 - j0 + 1); }
  // The frame's (x, y) of a point at fractional lattice node (i, j).
  std::array<double, 2> local(double i, double j) const {
    return to_local(i * h - centre.x_m, j * h - centre.y_m);
  }
};

// Maps between the lattice's grid and the frame, fitted on 5 x 5 points of the square of
// half-width `half_size_m` about `centre_m` (the region) at the
// ground's mean height: the frame's axes are not the local verticals, so a point's height moves
// its latitude and longitude, but by well under a millimetre within tens of metres of it.
LatticeRegion fit_region_maps(const GroundMesh& base, const LocalFrame& frame,
                              const std::array<double, 2>& centre_m, double half_size_m, double h) {
  const Geodetic& origin = frame.origin();
  const Zone zone = zone_of(origin.lat_deg, origin.lon_deg);
  const double z_ref_m = 0.5 * (base.min_height_m + base.max_height_m);
  const GridPoint centre = grid_point(zone, origin.lat_deg, origin.lon_deg);
  std::vector<std::array<double, 2>> local_points, grid_points;
  for (int b = -2; b <= 2; ++b) {
    for (int a = -2; a <= 2; ++a) {
      const double x = centre_m[0] + 0.5 * a * half_size_m, y = centre_m[1] + 0.5 * b * half_size_m;
      const Geodetic g = frame.to_geodetic({x, y, z_ref_m});
      const GridPoint p = grid_point(zone, g.lat_deg, g.lon_deg);
      local_points.push_back({x, y});
      grid_points.push_back({p.x_m - centre.x_m, p.y_m - centre.y_m});
    }
  }
  return {zone, centre, QuadraticMap(grid_points, local_points, half_size_m),
          QuadraticMap(local_points, grid_points, half_size_m), h};
}

// The lattice nodes [i0, i1] x [j0, j1] of one square of the frame.
struct NodeBox {
  std::int64_t i0 = 0, i1 = 0, j0 = 0, j1 = 0;
  bool holds(std::int64_t i, std::int64_t j) const {
    return i >= i0 && i <= i1 && j >= j0 && j <= j1;
  }
  // Nodes from (i, j) to the box's nearest edge.
  std::int64_t depth(std::int64_t i, std::int64_t j) const {
    return std::min({i - i0, i1 - i, j - j0, j1 - j});
  }
};

// The lattice nodes covering the square of the frame.
NodeBox cover_square(const LatticeRegion& region, const RoughSquare& square) {
  const double h = region.h, half_size_m = square.half_size_m;
  const double x0 = square.x_m - half_size_m, x1 = square.x_m + half_size_m;
  const double y0 = square.y_m - half_size_m, y1 = square.y_m + half_size_m;
  double gx0 = std::numeric_limits<double>::infinity(), gy0 = gx0, gx1 = -gx0, gy1 = -gx0;
  for (const auto& [x, y] : {std::array<double, 2>{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}) {
    const auto g = region.to_grid(x, y);
    gx0 = std::min(gx0, g[0] + region.centre.x_m);
    gx1 = std::max(gx1, g[0] + region.centre.x_m);
    gy0 = std::min(gy0, g[1] + region.centre.y_m);
    gy1 = std::max(gy1, g[1] + region.centre.y_m);
  }
  return {static_cast<std::int64_t>(std::floor(gx0 / h)),
          static_cast<std::int64_t>(std::ceil(gx1 / h)),
          static_cast<std::int64_t>(std::floor(gy0 / h)),
          static_cast<std::int64_t>(std::ceil(gy1 / h))};
}

// The union of boxes over the region's nodes: each node's depth in the box holding it deepest
// (-1 outside them all), and whether each cell lies in one box.
struct BoxUnion {
  BoxUnion(const LatticeRegion& region, std::vector<NodeBox> node_boxes)
      : boxes(std::move(node_boxes)),
        ni(region.ni()),
        depths(static_cast<std::size_t>(ni) * region.nj(), -1),
        cells(depths.size(), 0) {
    for (const NodeBox& box : boxes)
      for (std::int64_t j = box.j0; j <= box.j1; ++j)
        for (std::int64_t i = box.i0; i <= box.i1; ++i) {
          const std::size_t n = static_cast<std::size_t>(j - region.j0) * ni + (i - region.i0);
          depths[n] = std::max(depths[n], box.depth(i, j));
          if (i < box.i1 && j < box.j1) cells[n] = 1;
        }
  }
  std::int64_t depth(int i, int j) const { return depths[static_cast<std::size_t>(j) * ni + i]; }

  std::vector<NodeBox> boxes;
  int ni;
  std::vector<std::int64_t> depths;
  std::vector<char> cells;
};

std::uint32_t add_vertex(GroundMesh& mesh, double x, double y, double z) {
  mesh.vertices_m.insert(mesh.vertices_m.end(),
                         {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
  return static_cast<std::uint32_t>(mesh.vertices_m.size() / 3 - 1);
}

// A convex polygon as a fan of triangles of new vertices; slivers along an edge are left out.
void add_convex_polygon(const std::vector<ClipVertex>& polygon, GroundMesh& mesh) {
  if (polygon.size() < 3) return;
  double twice_area = 0.0;
  for (std::size_t k = 0; k < polygon.size(); ++k) {
    const ClipVertex& p = polygon[k];
    const ClipVertex& q = polygon[(k + 1) % polygon.size()];
    twice_area += p.x * q.y - q.x * p.y;
  }
  if (std::abs(twice_area) < 1e-8) return;
  const std::uint32_t first = add_vertex(mesh, polygon[0].x, polygon[0].y, polygon[0].z);
  std::uint32_t previous = add_vertex(mesh, polygon[1].x, polygon[1].y, polygon[1].z);
  for (std::size_t k = 2; k < polygon.size(); ++k) {
    const std::uint32_t next = add_vertex(mesh, polygon[k].x, polygon[k].y, polygon[k].z);
    mesh.triangles.insert(mesh.triangles.end(), {first, previous, next});
    previous = next;
  }
}

// The mesh's nodes on the base surface, raised by the relief: the lattice's nodes, or r times
// finer where the base has finer detail (a DEM of fine cells) so that its own relief stays.
// The field varies over a correlation length, three lattice steps: between nodes it is
// interpolated bilinearly. At most 1024 nodes a side: finer detail is then smoothed.
// Over several boxes, only the nodes and cells inside one of them.
void mesh_region(const GroundMesh& base, const LatticeRegion& region, const BoxUnion& boxes,
                 const std::vector<double>& relief_m, double base_spacing_m, GroundMesh& mesh) {
  const int ni = region.ni(), nj = region.nj();
  int r = 1;
  if (base_spacing_m < region.h) r = static_cast<int>(std::ceil(region.h / base_spacing_m - 1e-9));
  r = std::clamp(r, 1, std::max(1, 1023 / std::max(1, std::max(ni, nj) - 1)));
  const int fi = (ni - 1) * r + 1, fj = (nj - 1) * r + 1;
  auto relief_at = [&](int a, int b) {  // fine node (a, b): lattice (a / r, b / r)
    const int i = std::min(a / r, std::max(ni - 2, 0)), j = std::min(b / r, std::max(nj - 2, 0));
    const double u = static_cast<double>(a - i * r) / r, v = static_cast<double>(b - j * r) / r;
    auto at = [&](int ii, int jj) {
      return relief_m[static_cast<std::size_t>(std::min(jj, nj - 1)) * ni + std::min(ii, ni - 1)];
    };
    return (1 - u) * (1 - v) * at(i, j) + u * (1 - v) * at(i + 1, j) + (1 - u) * v * at(i, j + 1) +
           u * v * at(i + 1, j + 1);
  };
  const HeightIndex ground(base);
  std::vector<std::uint32_t> node_vertex(static_cast<std::size_t>(fi) * fj, no_vertex);
  mesh.vertices_m.reserve(mesh.vertices_m.size() + 3 * node_vertex.size());
  // Whether fine node (a, b) lies in the union (its lattice neighbours do), and whether the
  // fine cell from it lies in one box.
  auto node_in = [&](int a, int b) {
    return boxes.depth(a / r, b / r) >= 0 && boxes.depth((a + r - 1) / r, (b + r - 1) / r) >= 0;
  };
  auto cell_in = [&](int a, int b) {
    return boxes.cells[static_cast<std::size_t>(b / r) * ni + a / r] != 0;
  };
  for (int b = 0; b < fj; ++b)
    for (int a = 0; a < fi; ++a) {
      if (!node_in(a, b)) continue;
      const auto [x, y] = region.local(region.i0 + static_cast<double>(a) / r,
                                       region.j0 + static_cast<double>(b) / r);
      if (const auto z = ground.height_m(x, y))
        node_vertex[static_cast<std::size_t>(b) * fi + a] =
            add_vertex(mesh, x, y, *z + relief_at(a, b));
    }
  // Over several boxes, the cells inside a box alone: two boxes a cell apart leave the cell
  // between them to the base.
  std::vector<char> cells;
  if (boxes.boxes.size() > 1) {
    cells.assign(static_cast<std::size_t>(fi - 1) * (fj - 1), 0);
    for (int b = 0; b + 1 < fj; ++b)
      for (int a = 0; a + 1 < fi; ++a)
        cells[static_cast<std::size_t>(b) * (fi - 1) + a] = cell_in(a, b) ? 1 : 0;
  }
  mesh_grid_cells(fi, fj, node_vertex, cells, mesh);
}

// The base outside the boxes: each box's outline in the frame is a convex quadrilateral
// (counter-clockwise, as east and north are in both). A triangle that crosses one is cut along
// it; the outside is split into four convex parts (outside edge k, inside the edges before), and
// each part goes on to the next box.
void add_base_outside(const GroundMesh& base, const LatticeRegion& region,
                      const std::vector<NodeBox>& boxes, GroundMesh& mesh) {
  using Quad = std::array<std::array<double, 2>, 4>;
  std::vector<Quad> quads;
  for (const NodeBox& box : boxes)
    quads.push_back({region.local(box.i0, box.j0), region.local(box.i1, box.j0),
                     region.local(box.i1, box.j1), region.local(box.i0, box.j1)});
  auto side = [](const Quad& quad, int edge, const ClipVertex& v) {
    const auto& p = quad[edge];
    const auto& q = quad[(edge + 1) % 4];
    return (q[0] - p[0]) * (v.y - p[1]) - (q[1] - p[1]) * (v.x - p[0]);  // > 0 inside
  };
  // Whether some edge of the quad has every vertex outside it.
  auto disjoint = [&](const Quad& quad, const ClipVertex* polygon, std::size_t count) {
    for (int edge = 0; edge < 4; ++edge) {
      std::size_t outside = 0;
      for (std::size_t k = 0; k < count; ++k) outside += side(quad, edge, polygon[k]) < 0.0 ? 1 : 0;
      if (outside == count) return true;
    }
    return false;
  };
  std::vector<std::vector<ClipVertex>> parts, next;
  for (std::size_t t = 0; t < base.triangles.size(); t += 3) {
    std::array<ClipVertex, 3> corners;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = base.triangles[t + k];
      corners[k] = {base.vertices_m[3 * v], base.vertices_m[3 * v + 1], base.vertices_m[3 * v + 2]};
    }
    // Most of the base lies clear of every box: kept as it is, without the clipping's copies.
    if (std::all_of(quads.begin(), quads.end(),
                    [&](const Quad& quad) { return disjoint(quad, corners.data(), 3); })) {
      mesh.triangles.insert(mesh.triangles.end(), base.triangles.begin() + t,
                            base.triangles.begin() + t + 3);
      continue;
    }
    bool whole = true;  // the triangle untouched so far: kept as the base has it
    parts.assign(1, std::vector<ClipVertex>(corners.begin(), corners.end()));
    for (const Quad& quad : quads) {
      next.clear();
      for (const std::vector<ClipVertex>& polygon : parts) {
        bool disjoint = false, inside = true;
        for (int edge = 0; edge < 4; ++edge) {
          int outside = 0;
          for (const ClipVertex& p : polygon) outside += side(quad, edge, p) < 0.0 ? 1 : 0;
          disjoint = disjoint || outside == static_cast<int>(polygon.size());
          inside = inside && outside == 0;
        }
        if (disjoint) {
          next.push_back(polygon);
          continue;
        }
        whole = false;
        if (inside) continue;
        for (int edge = 0; edge < 4; ++edge) {
          std::vector<ClipVertex> part =
              clip(polygon, [&](const ClipVertex& p) { return -side(quad, edge, p); });
          for (int before = 0; before < edge && part.size() >= 3; ++before)
            part = clip(part, [&](const ClipVertex& p) { return side(quad, before, p); });
          if (part.size() >= 3) next.push_back(std::move(part));
        }
      }
      parts.swap(next);
    }
    if (whole) {
      mesh.triangles.insert(mesh.triangles.end(), base.triangles.begin() + t,
                            base.triangles.begin() + t + 3);
      continue;
    }
    for (const std::vector<ClipVertex>& part : parts) add_convex_polygon(part, mesh);
  }
}

}  // namespace

RoughnessField::Lattice::Lattice(double correlation_m, double rms_m, int nodes_per_correlation)
    : spacing_m(correlation_m / nodes_per_correlation) {
  // Noise smoothed by exp(-2 r^2 / L^2) has covariance exp(-r^2 / L^2); taps down to 1e-4.
  const int half_taps =
      static_cast<int>(std::ceil(std::sqrt(std::log(1e4) / 2.0) * correlation_m / spacing_m));
  for (int k = -half_taps; k <= half_taps; ++k) {
    const double r_m = k * spacing_m;
    kernel.push_back(std::exp(-2.0 * r_m * r_m / (correlation_m * correlation_m)));
  }
  // Covariance of smoothed nodes d apart along one axis: A(d) = sum_k a_k a_(k+d); in 2-D it is
  // A(di) A(dj). Over a lattice triangle the linear surface through nodes f_a has mean variance
  // sum_ab E[l_a l_b] C_ab, with E[l_a^2] = 1/6 and E[l_a l_b] = 1/12 for uniform barycentric
  // coordinates l: var(node) * (1/2 + (rho_10 + rho_01 + rho_11) / 6).
  double a0 = 0.0, a1 = 0.0;
  for (std::size_t k = 0; k < kernel.size(); ++k) {
    a0 += kernel[k] * kernel[k];
    if (k + 1 < kernel.size()) a1 += kernel[k] * kernel[k + 1];
  }
  const double rho = a1 / a0;
  const double surface_variance = a0 * a0 * (0.5 + (2.0 * rho + rho * rho) / 6.0);
  scale = rms_m / std::sqrt(surface_variance);
}

RoughnessField::RoughnessField(const RoughnessSettings& settings, std::uint64_t seed)
    : rms_m_(settings.rms_m), correlation_m_(settings.correlation_m), seed_(seed) {
  if (!enabled()) return;
  for (int nodes : nodes_per_correlation) lattices_.emplace_back(correlation_m_, rms_m_, nodes);
}

double RoughnessField::height_m(double lat_deg, double lon_deg, int level) const {
  if (!enabled()) return 0.0;
  const Lattice& lattice = lattices_.at(level);
  const Zone zone = zone_of(lat_deg, lon_deg);
  const GridPoint p = grid_point(zone, lat_deg, lon_deg);
  const double u = p.x_m / lattice.spacing_m, v = p.y_m / lattice.spacing_m;
  const auto i = static_cast<std::int64_t>(std::floor(u)),
             j = static_cast<std::int64_t>(std::floor(v));
  // The four nodes of the cell, on the lattice triangle holding the point, as the mesh has it.
  const std::vector<double> node = smoothed_noise(seed_, zone, level, lattice.kernel, i, j, 2, 2);
  return lattice.scale *
         cell_height(u - i, v - j, [&](int di, int dj) { return node[2 * dj + di]; });
}

namespace {

std::string metres(double value_m) {
  std::ostringstream text;
  text << std::setprecision(3) << value_m << " m";
  return text.str();
}

}  // namespace

Error RoughnessField::too_fine(double half_size_m, std::int64_t nodes_a_side) const {
  const double side_m = 2.0 * half_size_m;
  return setting_error(
      ErrorKind::config, "roughness/correlation_m",
      metres(correlation_m_) + " is too short to mesh under this beam: its field of view, " +
          metres(side_m) + " across, would need " + std::to_string(nodes_a_side) +
          " lattice nodes a side even at one node per correlation length, and the limit is " +
          std::to_string(max_nodes_a_side) + " (about " +
          metres(correlation_m_ * static_cast<double>(nodes_a_side) / max_nodes_a_side) +
          " at least; or a narrower field of view)");
}

GroundMesh RoughnessField::roughen(const GroundMesh& base, const LocalFrame& frame,
                                   double half_size_m, double base_spacing_m) const {
  if (half_size_m <= 0.0) return base;
  return roughen(base, frame, std::vector<RoughSquare>{{0.0, 0.0, half_size_m}}, base_spacing_m);
}

GroundMesh RoughnessField::roughen(const GroundMesh& base, const LocalFrame& frame,
                                   const std::vector<RoughSquare>& squares,
                                   double base_spacing_m) const {
  if (!enabled() || base.triangles.empty() || squares.empty()) return base;
  // The maps are fitted over the squares' bounding square.
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
  double widest_m = 0.0;
  for (const RoughSquare& square : squares) {
    if (!(square.half_size_m > 0.0)) return base;
    x0 = std::min(x0, square.x_m - square.half_size_m);
    x1 = std::max(x1, square.x_m + square.half_size_m);
    y0 = std::min(y0, square.y_m - square.half_size_m);
    y1 = std::max(y1, square.y_m + square.half_size_m);
    widest_m = std::max(widest_m, square.half_size_m);
  }
  const std::array<double, 2> centre_m =
      squares.size() == 1 ? std::array<double, 2>{squares[0].x_m, squares[0].y_m}
                          : std::array<double, 2>{0.5 * (x0 + x1), 0.5 * (y0 + y1)};
  const double fit_half_m =
      squares.size() == 1 ? squares[0].half_size_m : 0.5 * std::max(x1 - x0, y1 - y0);
  // The finest lattice whose nodes over each square stay within the limit.
  std::optional<LatticeRegion> fitted;
  std::vector<NodeBox> node_boxes;
  int level = 0;
  for (;; ++level) {
    fitted.emplace(fit_region_maps(base, frame, centre_m, fit_half_m, lattices_[level].spacing_m));
    node_boxes.clear();
    std::int64_t nodes_a_side = 0;
    for (const RoughSquare& square : squares) {
      node_boxes.push_back(cover_square(*fitted, square));
      nodes_a_side = std::max(nodes_a_side, std::max(node_boxes.back().i1 - node_boxes.back().i0,
                                                     node_boxes.back().j1 - node_boxes.back().j0) +
                                                1);
    }
    if (nodes_a_side <= max_nodes_a_side) break;
    if (level + 1 == static_cast<int>(lattices_.size())) throw too_fine(widest_m, nodes_a_side);
  }
  LatticeRegion& region = *fitted;
  region.i0 = region.j0 = std::numeric_limits<std::int64_t>::max();
  region.i1 = region.j1 = std::numeric_limits<std::int64_t>::min();
  for (const NodeBox& box : node_boxes) {
    region.i0 = std::min(region.i0, box.i0), region.i1 = std::max(region.i1, box.i1);
    region.j0 = std::min(region.j0, box.j0), region.j1 = std::max(region.j1, box.j1);
  }
  const Lattice& lattice = lattices_[level];
  const int ni = region.ni(), nj = region.nj();

  // The relief of every node of a box, tapering to nothing over the outer 2 correlation
  // lengths of the boxes' union (a node's depth in the box holding it deepest). A node's noise
  // is the same whichever box it is smoothed in.
  std::vector<double> relief_m;
  if (node_boxes.size() == 1) {
    relief_m =
        smoothed_noise(seed_, region.zone, level, lattice.kernel, region.i0, region.j0, ni, nj);
  } else {
    relief_m.assign(static_cast<std::size_t>(ni) * nj, 0.0);
    for (const NodeBox& box : node_boxes) {
      const int bi = static_cast<int>(box.i1 - box.i0 + 1),
                bj = static_cast<int>(box.j1 - box.j0 + 1);
      const std::vector<double> noise =
          smoothed_noise(seed_, region.zone, level, lattice.kernel, box.i0, box.j0, bi, bj);
      for (int j = 0; j < bj; ++j)
        for (int i = 0; i < bi; ++i)
          relief_m[static_cast<std::size_t>(box.j0 - region.j0 + j) * ni +
                   (box.i0 - region.i0 + i)] = noise[static_cast<std::size_t>(j) * bi + i];
    }
  }
  const BoxUnion boxes(region, std::move(node_boxes));
  const int ramp_nodes =
      std::max(1, static_cast<int>(std::lround(2.0 * correlation_m_ / region.h)));
  for (int j = 0; j < nj; ++j)
    for (int i = 0; i < ni; ++i) {
      const std::int64_t edge = std::max<std::int64_t>(0, boxes.depth(i, j));
      const double taper = std::min(1.0, static_cast<double>(edge) / ramp_nodes);
      relief_m[static_cast<std::size_t>(j) * ni + i] *= lattice.scale * taper;
    }

  GroundMesh mesh;
  mesh.vertices_m = base.vertices_m;
  mesh_region(base, region, boxes, relief_m, base_spacing_m, mesh);
  add_base_outside(base, region, boxes.boxes, mesh);
  mesh.min_height_m = std::numeric_limits<double>::infinity();
  mesh.max_height_m = -std::numeric_limits<double>::infinity();
  auto span = [&](std::uint32_t v) {
    mesh.min_height_m = std::min<double>(mesh.min_height_m, mesh.vertices_m[3 * v + 2]);
    mesh.max_height_m = std::max<double>(mesh.max_height_m, mesh.vertices_m[3 * v + 2]);
  };
  for (std::uint32_t v : mesh.triangles) span(v);
  for (const MeshGrid& grid : mesh.grids)
    for (std::uint32_t v : grid.nodes) span(v);
  if (mesh.triangles.empty() && mesh.grids.empty()) mesh.min_height_m = mesh.max_height_m = 0.0;
  return mesh;
}

}  // namespace glaswave
