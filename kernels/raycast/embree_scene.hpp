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
