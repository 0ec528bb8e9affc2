#pragma once
//! Embree 3 set-up shared by every ray-casting user (the alignment's TargetSurface, the renderer): one
//! device for the process, and a committed scene of one triangle geometry built from flat arrays.
//! Embree errors are recorded per thread and turned into typed exceptions; nothing is printed.
#include <embree3/rtcore.h>

#include <array>
#include <span>

#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

//! The process-wide Embree device: creating a device starts Embree's task system, far too costly to
//! repeat per frame. Thread-safe. \throw Error when Embree cannot create it.
RTCDevice embree_device();

//! The Embree kernels that device runs: "avx2" where the CPU has AVX2, else "sse4.2" ("native", Embree's own
//! choice, only off x86 or if neither can be set). Pinned, because Embree's kernels for different instruction sets
//! answer differently: output is bit-identical across machines that run the same kernels.
const char* embree_isa();

//! A ray from `origin` along `direction` (not normalised: t counts in its lengths) over t in [0, tfar], in
//! Embree's float layout, with no hit recorded yet: what rtcIntersect1 takes.
inline RTCRayHit embree_ray(const Vec3& origin, const Vec3& direction, float tfar) {
  RTCRayHit rh;
  rh.ray.org_x = float(origin.x());
  rh.ray.org_y = float(origin.y());
  rh.ray.org_z = float(origin.z());
  rh.ray.dir_x = float(direction.x());
  rh.ray.dir_y = float(direction.y());
  rh.ray.dir_z = float(direction.z());
  rh.ray.tnear = 0.0f;
  rh.ray.tfar = tfar;
  rh.ray.time = 0.0f;
  rh.ray.mask = ~0u;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

//! An owned, committed Embree scene holding `triangles` over `positions` (in float) as geometry 0, so
//! that a hit's primID is the triangle index. Move-only.
class EmbreeScene {
public:
  //! \throw InvalidInput when there are more triangles than Embree can index or an index is out of
  //! range; Error when Embree fails.
  EmbreeScene(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles,
              RTCBuildQuality quality = RTC_BUILD_QUALITY_LOW, RTCSceneFlags flags = RTC_SCENE_FLAG_ROBUST);
  EmbreeScene() = default;
  ~EmbreeScene();
  EmbreeScene(EmbreeScene&& other) noexcept;
  EmbreeScene& operator=(EmbreeScene&& other) noexcept;
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  RTCScene get() const { return scene_; }

private:
  RTCScene scene_ = nullptr;
};

}  // namespace topotrack
