#include "kernels/render/raytracer.hpp"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>

#include "io/error.hpp"
#include "kernels/raycast/embree_scene.hpp"

namespace topotrack {

struct RenderScene::Impl {
  RenderMesh mesh;
  std::vector<float> normals;  // 3 per vertex, area weighted, unit
  BoundingBox bounds;
  EmbreeScene scene;
  double build_seconds = 0;
};

RenderScene::RenderScene(RenderMesh mesh) : impl_(std::make_unique<Impl>()) {
  const auto t0 = std::chrono::steady_clock::now();
  Impl& m = *impl_;
  const std::size_t nv = mesh.positions.size();
  if (!mesh.colors.empty() && mesh.colors.size() != 3 * nv)
    TT_THROW(InvalidInput, "RenderScene: " << mesh.colors.size() << " colour values for " << nv << " vertices");
  if (nv >= std::numeric_limits<Index>::max()) TT_THROW(InvalidInput, "RenderScene: too many vertices");
  for (std::size_t i = 0; i < nv; ++i) {
    if (!mesh.positions[i].allFinite()) TT_THROW(InvalidInput, "RenderScene: vertex " << i << " is not finite");
    m.bounds.extend(mesh.positions[i]);
  }
  std::vector<double> acc(3 * nv, 0.0);
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    for (Index v : t)
      if (v >= nv) TT_THROW(InvalidInput, "RenderScene: triangle " << f << " has vertex index " << v << " >= " << nv);
    const Vec3 n = (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
    for (Index v : t)
      for (int c = 0; c < 3; ++c) acc[3 * v + c] += n[c];
  }
  m.normals.resize(3 * nv);
  for (std::size_t i = 0; i < nv; ++i) {
    const Vec3 n(acc[3 * i], acc[3 * i + 1], acc[3 * i + 2]);
    const double len = n.norm();
    for (int c = 0; c < 3; ++c) m.normals[3 * i + c] = len > 0 ? float(n[c] / len) : 0.0f;
  }

  // Medium quality: a picture casts ~10 rays per triangle, worth a better tree than the alignment's.
  m.scene = EmbreeScene(mesh.positions, mesh.triangles, RTC_BUILD_QUALITY_MEDIUM);
  m.mesh = std::move(mesh);
  m.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

RenderScene::~RenderScene() = default;
RenderScene::RenderScene(RenderScene&&) noexcept = default;
RenderScene& RenderScene::operator=(RenderScene&&) noexcept = default;
const RenderMesh& RenderScene::mesh() const { return impl_->mesh; }
BoundingBox RenderScene::bounds() const { return impl_->bounds; }
double RenderScene::build_seconds() const { return impl_->build_seconds; }

namespace {

struct Shader {
  const RenderScene::Impl& s;
  const RenderParams& p;
  Vec3 light, eye;
  double footprint_per_unit;  // pixel size at distance 1 along the ray

  // Shade one ray; returns whether it hit.
  bool shade(const Vec3& dir, std::array<double, 3>& rgb) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh = embree_ray(eye, dir, std::numeric_limits<float>::infinity());
    rtcIntersect1(s.scene.get(), &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
      for (int c = 0; c < 3; ++c) rgb[c] = p.background[c];
      return false;
    }
    const auto& tri = s.mesh.triangles[rh.hit.primID];
    const double b[3] = {1.0 - rh.hit.u - rh.hit.v, rh.hit.u, rh.hit.v};
    Vec3 ng(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    ng.normalize();
    if (ng.dot(dir) > 0) ng = -ng;
    Vec3 n = ng;
    if (p.smooth_shading) {
      Vec3 sn = Vec3::Zero();
      for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c) sn[c] += b[k] * s.normals[3 * tri[k] + c];
      if (sn.squaredNorm() > 1e-20) {
        sn.normalize();
        n = sn.dot(ng) < 0 ? Vec3(-sn) : sn;
      }
    }
    double albedo[3];
    if (s.mesh.colors.empty()) {
      for (int c = 0; c < 3; ++c) albedo[c] = p.base_color[c];
    } else {
      for (int c = 0; c < 3; ++c) {
        albedo[c] = 0;
        for (int k = 0; k < 3; ++k) albedo[c] += b[k] * s.mesh.colors[3 * tri[k] + c];
        albedo[c] = std::clamp(albedo[c], 0.0, 1.0);
      }
    }
    const double diffuse = p.ambient + p.key * std::max(0.0, n.dot(light)) + p.fill * std::max(0.0, -n.dot(dir));
    const Vec3 h = (light - dir).normalized();
    const double spec = p.specular * std::pow(std::max(0.0, n.dot(h)), 40.0);
    for (int c = 0; c < 3; ++c) rgb[c] = albedo[c] * diffuse + spec;
    if (p.wireframe) {
      const Vec3& p0 = s.mesh.positions[tri[0]];
      const Vec3& p1 = s.mesh.positions[tri[1]];
      const Vec3& p2 = s.mesh.positions[tri[2]];
      const double twice_area = (p1 - p0).cross(p2 - p0).norm();
      const double edge[3] = {(p2 - p1).norm(), (p0 - p2).norm(), (p1 - p0).norm()};
      double dist = std::numeric_limits<double>::infinity();
      for (int k = 0; k < 3; ++k)
        if (edge[k] > 0) dist = std::min(dist, b[k] * twice_area / edge[k]);
      if (dist < 0.5 * p.wire_width_px * footprint_per_unit * rh.ray.tfar)
        for (int c = 0; c < 3; ++c) rgb[c] = p.wire_color[c];
    }
    return true;
  }
};

}  // namespace

Image render(const RenderScene& scene, const Camera& camera, const RenderParams& params, RenderReport* report) {
  if (params.width < 1 || params.height < 1 || params.width > 16384 || params.height > 16384)
    TT_THROW(InvalidInput, "render: image size " << params.width << "x" << params.height << " not in [1, 16384]");
  if (params.samples_per_axis < 1 || params.samples_per_axis > 8)
    TT_THROW(InvalidInput, "render: samples per axis " << params.samples_per_axis << " not in [1, 8]");
  if (!(camera.fov_y_deg > 0 && camera.fov_y_deg < 180) || !((camera.target - camera.eye).norm() > 0))
    TT_THROW(InvalidInput, "render: degenerate camera");
  const auto t0 = std::chrono::steady_clock::now();
  const int W = params.width, H = params.height, ns = params.samples_per_axis;
  const Vec3 fwd = camera.forward(), right = camera.right(), up = camera.true_up();
  const double tan_half = std::tan(0.5 * camera.fov_y_deg * std::numbers::pi / 180);
  const double aspect = double(W) / H;
  Shader shader{scene.impl(), params, (0.5 * up - 0.45 * right - 0.75 * fwd).normalized(), camera.eye,
                2 * tan_half / H};

  Image image(W, H);
  std::vector<std::size_t> row_hits(H, 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, H, 4), [&](const tbb::blocked_range<int>& rows) {
    std::array<double, 3> rgb;
    for (int y = rows.begin(); y < rows.end(); ++y) {
      std::size_t hits = 0;
      for (int x = 0; x < W; ++x) {
        double sum[3] = {0, 0, 0};
        for (int sy = 0; sy < ns; ++sy)
          for (int sx = 0; sx < ns; ++sx) {
            const double px = (x + (sx + 0.5) / ns) / W * 2 - 1;
            const double py = 1 - (y + (sy + 0.5) / ns) / H * 2;
            const Vec3 dir = (fwd + px * tan_half * aspect * right + py * tan_half * up).normalized();
            hits += shader.shade(dir, rgb);
            for (int c = 0; c < 3; ++c) sum[c] += rgb[c];
          }
        std::uint8_t* out = image.pixel(x, y);
        for (int c = 0; c < 3; ++c)
          out[c] = std::uint8_t(std::lround(std::clamp(sum[c] / (ns * ns), 0.0, 1.0) * 255.0));
      }
      row_hits[y] = hits;
    }
  });
  if (report) {
    report->build_seconds = scene.build_seconds();
    report->rays = std::size_t(W) * H * ns * ns;
    std::size_t total = 0;
    for (std::size_t h : row_hits) total += h;
    report->covered_pixels = double(total) / (ns * ns);
    report->trace_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  return image;
}

Image render(RenderMesh mesh, const Camera& camera, const RenderParams& params, RenderReport* report) {
  const RenderScene scene(std::move(mesh));
  return render(scene, camera, params, report);
}

}  // namespace topotrack
