#include "kernels/raycast/embree_scene.hpp"

#include <utility>

#include "io/error.hpp"

namespace topotrack {
namespace {

thread_local RTCError tls_embree_error = RTC_ERROR_NONE;

void record_embree_error(void*, RTCError code, const char*) { tls_embree_error = code; }

struct PinnedDevice {
  RTCDevice device = nullptr;
  const char* isa = "native";
};

// Embree picks SSE4.2, AVX, AVX2 or AVX-512 kernels at run time, and they do not answer alike (BVH width and
// visiting order decide which face a hit on an edge or a vertex reports): resurfaced samba tracked with the
// SSE4.2 kernels and with the AVX2 ones part within a few frames. So every device runs the AVX2 kernels when the
// CPU has them (x86-64 CPUs since 2013; on this project's machine as fast as Embree's own choice, raycast_bench
// at 100k triangles), else the SSE4.2 ones. Test: EmbreeScene.PinsTheKernelsSoHitsAreTheSameOnEveryMachine.
const PinnedDevice& pinned_device() {
  static const PinnedDevice pinned = [] {
    PinnedDevice p;
#if defined(__x86_64__) || defined(__i386__)
    const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
                      __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2");
    const bool sse42 = __builtin_cpu_supports("sse4.2");
    if (avx2 && (p.device = rtcNewDevice("isa=avx2")))
      p.isa = "avx2";
    else if (sse42 && (p.device = rtcNewDevice("isa=sse4.2")))
      p.isa = "sse4.2";
#endif
    if (!p.device) p.device = rtcNewDevice(nullptr);
    if (!p.device)
      TT_THROW(Error, "Embree: cannot create a device (error " << int(rtcGetDeviceError(nullptr)) << ")");
    rtcSetDeviceErrorFunction(p.device, record_embree_error, nullptr);
    return p;
  }();
  return pinned;
}

}  // namespace

RTCDevice embree_device() { return pinned_device().device; }

const char* embree_isa() { return pinned_device().isa; }

EmbreeScene::EmbreeScene(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles,
                         RTCBuildQuality quality, RTCSceneFlags flags) {
  if (triangles.size() >= std::size_t(RTC_INVALID_GEOMETRY_ID))
    TT_THROW(InvalidInput, "Embree scene: too many triangles (" << triangles.size() << ")");
  const std::size_t nv = positions.size();
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (Index v : triangles[f])
      if (v >= nv) TT_THROW(InvalidInput, "Embree scene: triangle " << f << " has vertex index " << v << " >= " << nv);
  RTCDevice device = embree_device();
  tls_embree_error = RTC_ERROR_NONE;
  // The destructor does not run when the constructor throws: release the scene first.
  auto fail = [this](const char* what) {
    if (scene_) rtcReleaseScene(scene_);
    scene_ = nullptr;
    TT_THROW(Error, "Embree: " << what << " failed (error " << int(tls_embree_error) << ")");
  };
  scene_ = rtcNewScene(device);
  if (!scene_) fail("rtcNewScene");
  rtcSetSceneFlags(scene_, flags);
  rtcSetSceneBuildQuality(scene_, quality);
  if (!triangles.empty()) {
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!geom) fail("rtcNewGeometry");
    auto* vb = static_cast<float*>(
        rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv));
    auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                              3 * sizeof(unsigned), triangles.size()));
    if (!vb || !ib) {
      rtcReleaseGeometry(geom);
      fail("rtcSetNewGeometryBuffer");
    }
    for (std::size_t i = 0; i < nv; ++i)
      for (int c = 0; c < 3; ++c) vb[3 * i + c] = float(positions[i][c]);
    for (std::size_t f = 0; f < triangles.size(); ++f)
      for (int c = 0; c < 3; ++c) ib[3 * f + c] = triangles[f][c];
    rtcSetGeometryBuildQuality(geom, quality);
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(scene_, geom, 0);
    rtcReleaseGeometry(geom);
  }
  rtcCommitScene(scene_);
  if (tls_embree_error != RTC_ERROR_NONE) fail("rtcCommitScene");
}

EmbreeScene::~EmbreeScene() {
  if (scene_) rtcReleaseScene(scene_);
}

EmbreeScene::EmbreeScene(EmbreeScene&& other) noexcept : scene_(std::exchange(other.scene_, nullptr)) {}

EmbreeScene& EmbreeScene::operator=(EmbreeScene&& other) noexcept {
  if (this != &other) {
    if (scene_) rtcReleaseScene(scene_);
    scene_ = std::exchange(other.scene_, nullptr);
  }
  return *this;
}

}  // namespace topotrack
