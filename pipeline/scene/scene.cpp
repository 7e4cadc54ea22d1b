// Embree scenes of the ground (and later the canopy) in a shot's local frame.
#include "pipeline/scene/scene.hpp"

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include <embree3/rtcore.h>

#include "terrain/error.hpp"

namespace glaswave {
namespace {

void check_device(RTCDevice device, const char* what) {
  const RTCError code = rtcGetDeviceError(device);
  if (code != RTC_ERROR_NONE) throw run_error("Embree", std::string(what) + " failed (error " + std::to_string(code) + ")");
}

}  // namespace

RayDevice::RayDevice() : device_(rtcNewDevice(nullptr)) {
  if (!device_) throw run_error("Embree", "cannot create a ray tracing device");
}

RayDevice::~RayDevice() { rtcReleaseDevice(device_); }

Scene::Scene(const RayDevice& device, const GroundMesh& ground)
    : scene_(rtcNewScene(device.handle())), top_m_(ground.max_height_m) {
  check_device(device.handle(), "creating a scene");
  if (!ground.triangles.empty()) {
    RTCGeometry mesh = rtcNewGeometry(device.handle(), RTC_GEOMETRY_TYPE_TRIANGLE);
    const std::size_t vertex_count = ground.vertices_m.size() / 3;
    const std::size_t triangle_count = ground.triangles.size() / 3;
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(mesh, RTC_BUFFER_TYPE_VERTEX, 0,
                                                                 RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertex_count));
    auto* triangles = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        mesh, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), triangle_count));
    check_device(device.handle(), "allocating the ground mesh");
    std::memcpy(vertices, ground.vertices_m.data(), ground.vertices_m.size() * sizeof(float));
    std::memcpy(triangles, ground.triangles.data(), ground.triangles.size() * sizeof(unsigned));
    rtcCommitGeometry(mesh);
    rtcAttachGeometry(scene_, mesh);
    rtcReleaseGeometry(mesh);
  }
  rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
  rtcCommitScene(scene_);
  check_device(device.handle(), "building the scene");
}

Scene::~Scene() { rtcReleaseScene(scene_); }

SurfaceHit Scene::intersect(const Vec3& origin, const Vec3& direction, double max_distance_m) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit query{};
  query.ray.org_x = static_cast<float>(origin[0]);
  query.ray.org_y = static_cast<float>(origin[1]);
  query.ray.org_z = static_cast<float>(origin[2]);
  query.ray.dir_x = static_cast<float>(direction[0]);
  query.ray.dir_y = static_cast<float>(direction[1]);
  query.ray.dir_z = static_cast<float>(direction[2]);
  query.ray.tnear = 0.0f;
  query.ray.tfar = static_cast<float>(max_distance_m);
  query.ray.mask = std::numeric_limits<unsigned>::max();
  query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  query.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene_, &context, &query);

  SurfaceHit hit;
  if (query.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
  hit.kind = SurfaceKind::ground;
  hit.distance_m = query.ray.tfar;
  Vec3 normal = normalized(Vec3{query.hit.Ng_x, query.hit.Ng_y, query.hit.Ng_z});
  if (dot(normal, direction) > 0.0) normal = -1.0 * normal;
  hit.normal = normal;
  return hit;
}

}  // namespace glaswave
