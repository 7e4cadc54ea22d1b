// Which stand polygon holds a point, at a cost that does not grow with the number of stands nor
// with their vertices: GEOS's STRtree over the stands' bounding boxes, then, inside a stand, the
// even-odd rule over only the edges that span the point's latitude (edges kept in bands of
// latitude). The rule and its arithmetic are those of the loop over every edge
// (inside_by_every_edge), so a point gets the same answer, bit for bit, as without the index.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "canopy/canopy_settings.hpp"
#include "canopy/stand.hpp"

namespace glaswave {

// The even-odd rule over all rings of a stand (a point is inside when an odd number of rings hold
// it), every edge tried: the definition StandIndex keeps.
bool inside_by_every_edge(const StandArea& area, double lon_deg, double lat_deg);

class StandIndex {
 public:
  explicit StandIndex(const std::vector<StandArea>& areas);
  ~StandIndex();
  StandIndex(const StandIndex&) = delete;
  StandIndex& operator=(const StandIndex&) = delete;

  std::size_t size() const { return areas_.size(); }

  // 1 + the index of the last stand holding the point (later stands lie over earlier ones), or 0.
  int area_at(double lon_deg, double lat_deg) const;

  // The same among `candidates` alone, sorted highest first: they must hold every stand whose
  // box holds the point (areas_meeting a box around it), so that the answer is area_at's. A
  // shot asks this of each of its trees: one search of the tree a shot, not one a tree.
  int area_at(double lon_deg, double lat_deg, const std::vector<int>& candidates) const;

  // A stand's bounding box, a little wider in longitude: every point it holds is in there.
  TileBox box(int area) const;

  // The stands whose bounding boxes meet the box [lon0, lon1] x [lat0, lat1], in no order.
  std::vector<int> areas_meeting(double lon0_deg, double lat0_deg, double lon1_deg,
                                 double lat1_deg) const;

 private:
  struct Edge {
    double a_lon, a_lat, b_lon, b_lat;  // as the rule takes them: a = ring[i], b = ring[i - 1]
  };
  // One stand's edges, listed again in every band of latitude they span (CSR by band).
  struct Area {
    double lon0 = 0, lat0 = 0, lon1 = 0, lat1 = 0;  // bounding box of the vertices
    double band_deg = 1.0;
    int bands = 1;
    std::vector<std::uint32_t> band_start;
    std::vector<Edge> edges;
    int band_of(double lat_deg) const;
  };
  static Area index_area(const StandArea& area);
  bool inside(const Area& area, double lon_deg, double lat_deg) const;
  std::vector<int> query(double lon0_deg, double lat0_deg, double lon1_deg, double lat1_deg) const;

  std::vector<Area> areas_;
  void* tree_ = nullptr;  // GEOSSTRtree of the stands' boxes; items are 1 + the stand's index
};

}  // namespace glaswave
