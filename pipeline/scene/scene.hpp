// The scene of one shot, in its local east-north-up frame, held by Embree in single precision:
// the ground mesh now, crowns later. Ray origins are placed just above the scene so that
// float coordinates stay small (PHYSICS.md section 0).
#pragma once

#include <memory>

#include "terrain/ground_mesh.hpp"

struct RTCDeviceTy;
struct RTCSceneTy;

namespace glaswave {

// One Embree device per run, shared by every thread.
class RayDevice {
 public:
  RayDevice();
  ~RayDevice();
  RayDevice(const RayDevice&) = delete;
  RayDevice& operator=(const RayDevice&) = delete;
  RTCDeviceTy* handle() const { return device_; }

 private:
  RTCDeviceTy* device_;
};

enum class SurfaceKind { none, ground };

struct SurfaceHit {
  SurfaceKind kind = SurfaceKind::none;
  double distance_m = 0.0;  // along the ray from its origin
  Vec3 normal{};            // unit, on the side the ray came from
};

class Scene {
 public:
  Scene(const RayDevice& device, const GroundMesh& ground);
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  // The nearest surface along origin + t * direction for t in (0, max_distance_m].
  // Thread-safe.
  SurfaceHit intersect(const Vec3& origin, const Vec3& direction, double max_distance_m) const;

  double top_m() const { return top_m_; }  // highest point of any surface, local frame

 private:
  RTCSceneTy* scene_;
  double top_m_;
};

}  // namespace glaswave
