#include "kernels/sdf/signed_distance.hpp"

#include "kernels/sdf/exact_sign.hpp"
#include "kernels/sdf/narrow_band.hpp"
#include "kernels/sdf/thicken.hpp"

#include <chrono>
#include <cmath>
#include <mutex>
#include <openvdb/tools/MeshToVolume.h>

#include "kernels/mesh/mesh_convert.hpp"

namespace topotrack {
namespace {

// OpenVDB's own adapter over float copies in index space: libopenvdb exports meshToVolume's instantiation for
// exactly this adapter and NullInterrupter (an extern template in MeshToVolume.h), so this file compiles none of
// it. An adapter over our arrays cost 93 s of compile time in Release (the build's longest file, about 200 s
// under the sanitizers) to save a copy of 12 bytes per vertex and triangle.
struct IndexSpaceMesh {
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec3I> adapter() const {
    return {points, triangles};
  }
};

IndexSpaceMesh index_space_mesh(std::span<const Vec3> p, std::span<const std::array<Index, 3>> t, double inv_h) {
  IndexSpaceMesh m;
  m.points.resize(p.size());
  m.triangles.resize(t.size());
  for (std::size_t i = 0; i < p.size(); ++i)
    m.points[i] = openvdb::Vec3s(float(p[i].x() * inv_h), float(p[i].y() * inv_h), float(p[i].z() * inv_h));
  for (std::size_t f = 0; f < t.size(); ++f) m.triangles[f] = openvdb::Vec3I(t[f][0], t[f][1], t[f][2]);
  return m;
}

}  // namespace

void ensure_openvdb_initialized() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

openvdb::math::Transform::Ptr voxel_transform(double voxel_size) {
  if (!std::isfinite(voxel_size) || voxel_size <= 0)
    TT_THROW(InvalidInput, "signed distance: voxel size must be finite and positive, got " << voxel_size);
  try {
    return openvdb::math::Transform::createLinearTransform(voxel_size);
  } catch (const openvdb::Exception& e) {
    TT_THROW(InvalidInput, "signed distance: voxel size " << voxel_size << " rejected by OpenVDB: " << e.what());
  }
}

void check_signed_distance_input(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles,
                                 double half_width_voxels) {
  if (!std::isfinite(half_width_voxels) || half_width_voxels < 1.0)
    TT_THROW(InvalidInput, "signed distance: half width must be at least 1 voxel, got " << half_width_voxels);
  for (std::size_t i = 0; i < positions.size(); ++i)
    if (!positions[i].allFinite()) TT_THROW(InvalidInput, "signed distance: vertex " << i << " is not finite");
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (Index v : triangles[f])
      if (v >= positions.size())
        TT_THROW(InvalidInput, "signed distance: triangle " << f << " has vertex index " << v << " out of range ("
                                                            << positions.size() << " vertices)");
}

openvdb::math::Transform::Ptr lattice_transform(double voxel_size, const Vec3& origin) {
  auto xform = voxel_transform(voxel_size);
  if (!origin.allFinite()) TT_THROW(InvalidInput, "signed distance: the lattice's origin is not finite");
  if (!origin.isZero()) xform->postTranslate(openvdb::Vec3d(origin.x(), origin.y(), origin.z()));
  return xform;
}

bool is_lattice(const openvdb::math::Transform& xform, double voxel_size, const Vec3& origin) {
  if (!xform.isLinear() || !(voxel_size > 0)) return false;
  const double tol = 1e-9 * voxel_size;
  const openvdb::Vec3d o = xform.indexToWorld(openvdb::Vec3d(0, 0, 0));
  for (int a = 0; a < 3; ++a) {
    if (std::abs(o[a] - origin[a]) > tol) return false;
    openvdb::Vec3d e(0, 0, 0);
    e[a] = 1;
    const openvdb::Vec3d step = xform.indexToWorld(e) - o;
    for (int b = 0; b < 3; ++b)
      if (std::abs(step[b] - (a == b ? voxel_size : 0.0)) > tol) return false;
  }
  return true;
}

openvdb::FloatGrid::Ptr signed_distance(std::span<const Vec3> positions,
                                        std::span<const std::array<Index, 3>> triangles,
                                        const SignedDistanceParams& params, SignedDistanceReport* report) {
  using Clock = std::chrono::steady_clock;
  ensure_openvdb_initialized();
  if (!params.origin.isZero()) {
    // The lattice through `origin`: the distance to the mesh moved by -origin on the plain lattice, then the
    // grid's transform moved back (distances do not change under a translation).
    auto xform = lattice_transform(params.voxel_size, params.origin);
    std::vector<Vec3> moved(positions.begin(), positions.end());
    for (Vec3& p : moved) p -= params.origin;
    SignedDistanceParams at_zero = params;
    at_zero.origin = Vec3::Zero();
    auto grid = signed_distance(moved, triangles, at_zero, report);
    grid->setTransform(xform);
    return grid;
  }
  const double voxel_size = params.voxel_size, half_width_voxels = params.half_width_voxels;
  auto xform = voxel_transform(voxel_size);
  check_signed_distance_input(positions, triangles, half_width_voxels);
  if (!std::isfinite(params.min_thickness_voxels) || params.min_thickness_voxels < 0 ||
      (params.min_thickness_voxels > 0 && half_width_voxels < 0.5 * params.min_thickness_voxels + 1.5))
    TT_THROW(InvalidInput, "signed distance: a minimum thickness of " << params.min_thickness_voxels
                                                                      << " voxels needs a half width of at least "
                                                                      << 0.5 * params.min_thickness_voxels + 1.5
                                                                      << " voxels, got " << half_width_voxels);
  SignedDistanceReport rep;
  rep.method = params.method;
  if (rep.method == SdfMethod::kAuto)
    rep.method = params.sign_method == SignMethod::kPseudonormal && params.min_thickness_voxels == 0 &&
                         narrow_band_fits(positions, triangles, voxel_size, half_width_voxels)
                     ? SdfMethod::kNarrowBand
                     : SdfMethod::kOpenVdb;
  if (rep.method == SdfMethod::kNarrowBand) {
    if (params.min_thickness_voxels > 0)
      TT_THROW(InvalidInput, "signed distance: the narrow-band method does not thicken thin parts");
    const auto t0 = Clock::now();
    NarrowBandReport nb;
    openvdb::FloatGrid::Ptr grid =
        narrow_band_signed_distance(positions, triangles, {voxel_size, half_width_voxels}, &nb);
    rep.seconds_volume = std::chrono::duration<double>(Clock::now() - t0).count();
    rep.active_voxels = nb.active_voxels;
    if (report) *report = rep;
    return grid;
  }
  const float hw = static_cast<float>(half_width_voxels);
  openvdb::FloatGrid::Ptr grid;
  if (triangles.empty()) {
    grid = openvdb::FloatGrid::create(static_cast<float>(voxel_size * half_width_voxels));
  } else {
    const auto t0 = Clock::now();
    const IndexSpaceMesh mesh = index_space_mesh(positions, triangles, 1.0 / voxel_size);
    openvdb::util::NullInterrupter interrupter;
    grid = openvdb::tools::meshToVolume<openvdb::FloatGrid>(interrupter, mesh.adapter(), *xform, hw, hw, 0, nullptr);
    grid->setTransform(xform);
    const auto t1 = Clock::now();
    // OpenVDB's sign next to the surface can be wrong at concave creases and where the surface crosses
    // itself (see exact_sign.hpp).
    if (params.exact_sign_band_voxels > 0)
      rep.signs_flipped = correct_signs_near_surface(*grid, positions, triangles,
                                                     params.exact_sign_band_voxels * voxel_size, params.sign_method);
    const auto t2 = Clock::now();
    if (params.min_thickness_voxels > 0) {
      const auto thick = thicken_thin_parts(*grid, positions, triangles, {params.min_thickness_voxels * voxel_size});
      rep.thin_vertices = thick.thin_vertices;
      rep.thickened_voxels = thick.voxels_changed;
    }
    const auto t3 = Clock::now();
    rep.seconds_volume = std::chrono::duration<double>(t1 - t0).count();
    rep.seconds_sign = std::chrono::duration<double>(t2 - t1).count();
    rep.seconds_thicken = std::chrono::duration<double>(t3 - t2).count();
  }
  grid->setTransform(xform);
  grid->setGridClass(openvdb::GRID_LEVEL_SET);
  rep.active_voxels = grid->activeVoxelCount();
  if (report) *report = rep;
  return grid;
}

openvdb::FloatGrid::Ptr signed_distance(std::span<const Vec3> positions,
                                        std::span<const std::array<Index, 3>> triangles, double voxel_size,
                                        double half_width_voxels, double exact_sign_band_voxels) {
  SignedDistanceParams p;
  p.voxel_size = voxel_size;
  p.half_width_voxels = half_width_voxels;
  p.exact_sign_band_voxels = exact_sign_band_voxels;
  return signed_distance(positions, triangles, p);
}

openvdb::FloatGrid::Ptr signed_distance(const SurfaceMesh& mesh, double voxel_size, double half_width_voxels,
                                        double exact_sign_band_voxels, const Vec3& origin) {
  std::vector<Vec3> positions;
  std::vector<std::array<Index, 3>> triangles;
  extract_triangles(mesh, positions, triangles);
  SignedDistanceParams p;
  p.voxel_size = voxel_size;
  p.origin = origin;
  p.half_width_voxels = half_width_voxels;
  p.exact_sign_band_voxels = exact_sign_band_voxels;
  return signed_distance(positions, triangles, p);
}

}  // namespace topotrack
