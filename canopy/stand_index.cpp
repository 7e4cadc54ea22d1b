// The stands' spatial index: GEOS STRtree over boxes, bands of latitude over edges.
#include "canopy/stand_index.hpp"

#include <geos_c.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace glaswave {
namespace {

// The interpolated longitude of an edge at a latitude can stray an ulp or so beyond the edge's
// ends: boxes are this much wider in longitude, so that nothing the rule would count is missed.
constexpr double box_margin_deg = 1e-9;

// One context per thread: GEOS's reentrant API forbids sharing one between threads at once.
GEOSContextHandle_t geos() {
  struct Context {
    GEOSContextHandle_t handle = GEOS_init_r();
    ~Context() { GEOS_finish_r(handle); }
  };
  thread_local Context context;
  return context.handle;
}

// Whether the edge from a to b counts as a crossing of the ray from (lon, lat) towards east.
inline bool crosses(double a_lon, double a_lat, double b_lon, double b_lat, double lon_deg,
                    double lat_deg) {
  return (a_lat > lat_deg) != (b_lat > lat_deg) &&
         lon_deg < (b_lon - a_lon) * (lat_deg - a_lat) / (b_lat - a_lat) + a_lon;
}

void collect(void* item, void* userdata) {
  static_cast<std::vector<int>*>(userdata)->push_back(
      static_cast<int>(reinterpret_cast<std::intptr_t>(item) - 1));
}

}  // namespace

bool inside_by_every_edge(const StandArea& area, double lon_deg, double lat_deg) {
  bool in = false;
  for (const auto& ring : area.rings)
    for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++)
      if (crosses(ring[i][0], ring[i][1], ring[j][0], ring[j][1], lon_deg, lat_deg)) in = !in;
  return in;
}

int StandIndex::Area::band_of(double lat_deg) const {
  const double band = std::floor((lat_deg - lat0) / band_deg);
  return static_cast<int>(std::clamp(band, 0.0, static_cast<double>(bands - 1)));
}

// A stand's edges in bands of latitude: about 8 edges a band, fewer bands while long edges
// would be listed more than 4 times over on average.
StandIndex::Area StandIndex::index_area(const StandArea& stand) {
  Area area;
  std::vector<Edge> edges;
  area.lon0 = area.lat0 = INFINITY;
  area.lon1 = area.lat1 = -INFINITY;
  for (const auto& ring : stand.rings)
    for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
      edges.push_back({ring[i][0], ring[i][1], ring[j][0], ring[j][1]});
      area.lon0 = std::min(area.lon0, ring[i][0]), area.lon1 = std::max(area.lon1, ring[i][0]);
      area.lat0 = std::min(area.lat0, ring[i][1]), area.lat1 = std::max(area.lat1, ring[i][1]);
    }
  if (edges.empty()) return area;
  auto span = [&](const Edge& e) {
    return std::pair{area.band_of(std::min(e.a_lat, e.b_lat)),
                     area.band_of(std::max(e.a_lat, e.b_lat))};
  };
  std::size_t listed = 0;
  for (area.bands = static_cast<int>(std::clamp<std::size_t>(edges.size() / 8, 1, 1 << 20));;
       area.bands /= 2) {
    area.band_deg = area.lat1 > area.lat0 ? (area.lat1 - area.lat0) / area.bands : 1.0;
    listed = 0;
    for (const Edge& e : edges) listed += span(e).second - span(e).first + 1;
    if (area.bands == 1 || listed <= 4 * edges.size()) break;
  }
  area.band_start.assign(area.bands + 1, 0);
  for (const Edge& e : edges)
    for (int b = span(e).first; b <= span(e).second; ++b) ++area.band_start[b + 1];
  for (int b = 0; b < area.bands; ++b) area.band_start[b + 1] += area.band_start[b];
  area.edges.resize(listed);
  std::vector<std::uint32_t> fill(area.band_start.begin(), area.band_start.end() - 1);
  for (const Edge& e : edges)
    for (int b = span(e).first; b <= span(e).second; ++b) area.edges[fill[b]++] = e;
  return area;
}

StandIndex::StandIndex(const std::vector<StandArea>& areas) {
  for (const StandArea& area : areas) areas_.push_back(index_area(area));
  GEOSContextHandle_t handle = geos();
  tree_ = GEOSSTRtree_create_r(handle, 10);
  for (std::size_t k = 0; k < areas_.size(); ++k) {
    const Area& a = areas_[k];
    if (a.edges.empty()) continue;
    GEOSGeometry* box = GEOSGeom_createRectangle_r(handle, a.lon0 - box_margin_deg, a.lat0,
                                                   a.lon1 + box_margin_deg, a.lat1);
    if (!box) continue;  // not a number: the rule holds nothing
    // The tree keeps the box's envelope, not the geometry.
    GEOSSTRtree_insert_r(handle, static_cast<GEOSSTRtree*>(tree_), box,
                         reinterpret_cast<void*>(static_cast<std::intptr_t>(k + 1)));
    GEOSGeom_destroy_r(handle, box);
  }
  // The tree builds itself on its first query: done here, so that queries from many threads
  // only read it.
  query(0.0, 0.0, 0.0, 0.0);
}

StandIndex::~StandIndex() { GEOSSTRtree_destroy_r(geos(), static_cast<GEOSSTRtree*>(tree_)); }

std::vector<int> StandIndex::query(double lon0_deg, double lat0_deg, double lon1_deg,
                                   double lat1_deg) const {
  std::vector<int> found;
  GEOSContextHandle_t handle = geos();
  GEOSGeometry* box =
      lon0_deg == lon1_deg && lat0_deg == lat1_deg
          ? GEOSGeom_createPointFromXY_r(handle, lon0_deg, lat0_deg)
          : GEOSGeom_createRectangle_r(handle, lon0_deg, lat0_deg, lon1_deg, lat1_deg);
  if (!box) return found;  // not a number
  GEOSSTRtree_query_r(handle, static_cast<GEOSSTRtree*>(tree_), box, collect, &found);
  GEOSGeom_destroy_r(handle, box);
  return found;
}

bool StandIndex::inside(const Area& area, double lon_deg, double lat_deg) const {
  // Beyond the box no edge is crossed (north, south, east), or all are, an even number (west).
  if (area.edges.empty() || !(lat_deg >= area.lat0 && lat_deg < area.lat1) ||
      lon_deg < area.lon0 - box_margin_deg || lon_deg > area.lon1 + box_margin_deg)
    return false;
  // Only edges spanning lat_deg can be crossed, and they are all in its band.
  const int band = area.band_of(lat_deg);
  bool in = false;
  for (std::uint32_t e = area.band_start[band]; e < area.band_start[band + 1]; ++e) {
    const Edge& edge = area.edges[e];
    if (crosses(edge.a_lon, edge.a_lat, edge.b_lon, edge.b_lat, lon_deg, lat_deg)) in = !in;
  }
  return in;
}

int StandIndex::area_at(double lon_deg, double lat_deg) const {
  if (areas_.empty()) return 0;
  std::vector<int> candidates = query(lon_deg, lat_deg, lon_deg, lat_deg);
  std::sort(candidates.begin(), candidates.end(), std::greater<>());
  for (int k : candidates)
    if (inside(areas_[k], lon_deg, lat_deg)) return k + 1;
  return 0;
}

int StandIndex::area_at(double lon_deg, double lat_deg, const std::vector<int>& candidates) const {
  for (int k : candidates)
    if (inside(areas_[k], lon_deg, lat_deg)) return k + 1;
  return 0;
}

TileBox StandIndex::box(int area) const {
  const Area& a = areas_[area];
  return {a.lon0 - box_margin_deg, a.lat0, a.lon1 + box_margin_deg, a.lat1};
}

std::vector<int> StandIndex::areas_meeting(double lon0_deg, double lat0_deg, double lon1_deg,
                                           double lat1_deg) const {
  if (areas_.empty()) return {};
  return query(lon0_deg, lat0_deg, lon1_deg, lat1_deg);
}

}  // namespace glaswave
