// The ground as a height field: heights above the WGS84 ellipsoid by geodetic position,
// from a DEM or a synthetic plane, and the triangles a shot's scene is made of.
#pragma once

#include <memory>
#include <string>

#include "terrain/local_frame.hpp"
#include "terrain/terrain_settings.hpp"

namespace glaswave {

struct GroundMesh;  // terrain/ground_mesh.hpp

// How a terrain's heights were brought to the WGS84 ellipsoid: what the products record.
struct VerticalDatum {
  // As terrain.vertical_datum takes it: "ellipsoid", "egm96", or a vertical CRS ("EPSG:5773").
  std::string key = "ellipsoid";
  std::string description = "heights above the WGS84 ellipsoid";  // in words, for the summary
};

class Terrain {
 public:
  virtual ~Terrain() = default;

  // Height above the WGS84 ellipsoid (m) at a geodetic position, NaN where there is no data.
  virtual double height_m(double lat_deg, double lon_deg) const = 0;

  // The spacing (m) at which the terrain carries detail: a mesh finer than this adds nothing.
  virtual double detail_m() const = 0;

  // The ground over (at least) the square of half-width `half_size_m` about the frame's origin,
  // as triangles in the frame that interpolate exactly as height_m does, so that a footprint's
  // height and the surface its rays meet agree. Cells over missing data are left out. The
  // default samples height_m on a regular grid at most `spacing_m` apart, which is exact for
  // terrains that are planar between samples; a DEM overrides it with its own grid nodes.
  // Callers use build_ground_mesh (terrain/ground_mesh.hpp), which adds roughness.
  virtual GroundMesh mesh(const LocalFrame& frame, double half_size_m, double spacing_m) const;

  // Whether there is data everywhere within `radius_m` (horizontally) of the frame's origin:
  // a footprint over a hole or off the edge of a DEM is flagged rather than simulated.
  virtual bool has_data(const LocalFrame& frame, double radius_m) const;

  virtual VerticalDatum vertical_datum() const { return {}; }
};

// A tilted plane: heights fall by tan(slope) per metre toward the aspect, measured in the
// east-north plane of the origin's local tangent frame.
class PlaneTerrain final : public Terrain {
 public:
  explicit PlaneTerrain(const PlaneSettings& plane);
  double height_m(double lat_deg, double lon_deg) const override;
  double detail_m() const override { return 1.0e9; }
  // A plane has a height everywhere: no samples asked (17 a footprint, 2 % of a 19-ray shot).
  bool has_data(const LocalFrame&, double) const override { return true; }

 private:
  struct Frame;
  std::shared_ptr<const Frame> origin_;  // GeographicLib frame at the origin
  double elevation_m_;
  double east_gradient_;   // dh/de
  double north_gradient_;  // dh/dn
};

// The terrain the settings describe. A DEM that cannot be used throws an input error (exit
// status 3) naming the file and the cause.
std::unique_ptr<Terrain> make_terrain(const TerrainSettings& settings);

}  // namespace glaswave
