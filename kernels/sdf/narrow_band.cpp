#include "kernels/sdf/narrow_band.hpp"

#include <openvdb/tools/SignedFloodFill.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include <immintrin.h>

#include "io/error.hpp"
#include "kernels/mesh/radix_sort.hpp"
#include "kernels/sdf/signed_distance.hpp"

namespace topotrack {
namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

constexpr int kBlockLog = 4, kBlock = 1 << kBlockLog, kBlockVoxels = kBlock * kBlock * kBlock;
constexpr int kKeyBits = 10;  // per axis, relative block coordinates: 1024 blocks of 16 voxels
constexpr double kFixed = 1048576.0;  // 2^20: fixed-point resolution of the sign test, in voxels
constexpr double kMaxCoordinate = 1073741824.0;  // 2^30 voxels: fixed point stays in 51 bits

__extension__ typedef __int128 I128;

std::int64_t floor_div(std::int64_t a, std::int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }
int floor_block(int v) { return v >> kBlockLog; }  // arithmetic shift: floor for negative v

// Squared distance from p to triangle (a, b, c) (Ericson, Real-Time Collision Detection §5.1.5), the
// face region through the unit normal `n` (exact plane distance; n = 0 for a degenerate triangle).
double point_triangle_d2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& n) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.squaredNorm();
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double den = d1 - d3;
    return den > 0 ? (ap - (d1 / den) * ab).squaredNorm() : ap.squaredNorm();
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.squaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double den = d2 - d6;
    return den > 0 ? (ap - (d2 / den) * ac).squaredNorm() : ap.squaredNorm();
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double den = (d4 - d3) + (d5 - d6);
    return den > 0 ? (bp - ((d4 - d3) / den) * (c - b)).squaredNorm() : bp.squaredNorm();
  }
  if (n.squaredNorm() > 0) {
    const double h = n.dot(ap);
    return h * h;
  }
  // Degenerate (zero-area) triangle reaching the face case through rounding: nearest of its corners.
  return std::min({ap.squaredNorm(), bp.squaredNorm(), cp.squaredNorm()});
}

// The corners and edges of a triangle as the column kernels read them.
struct TriangleFrame {
  Vec3 A, B, C, n, ab, ac, bc;
  bool has_normal = false;
  Vec3 centre;     // of the bounding ball
  double R2 = 0;   // squared radius of the bounding ball widened by the half width
  int lo[3], hi[3];  // its voxel box, block-relative, clipped to the block
};

// The z-range of column (x, y) of the block at `org` inside the triangle's widened ball and box.
inline bool column_range(const TriangleFrame& t, double px, double py, int oz, int& z0, int& z1) {
  const double rem = t.R2 - (px - t.centre.x()) * (px - t.centre.x()) - (py - t.centre.y()) * (py - t.centre.y());
  if (rem < 0) return false;
  const double half = std::sqrt(rem);
  z0 = std::max(t.lo[2], int(std::ceil(t.centre.z() - half)) - oz);
  z1 = std::min(t.hi[2], int(std::floor(t.centre.z() + half)) - oz);
  return z0 <= z1;
}

// One column of a block: voxels (px, py, oz + z) for z in [z0, z1] against one triangle; row[z] keeps the
// minimum squared distance (plane test, then point_triangle_d2).
void column_scalar(const TriangleFrame& t, double px, double py, double oz, int z0, int z1, double* row) {
  Vec3 p(px, py, 0);
  for (int z = z0; z <= z1; ++z) {
    p.z() = oz + z;
    const double hp = t.n.dot(p - t.A);
    if (hp * hp >= row[z]) continue;  // the plane is a lower bound
    const double d = point_triangle_d2(p, t.A, t.B, t.C, t.n);
    if (d < row[z]) row[z] = d;  // strict: ties keep the smaller triangle index
  }
}

// The same, four voxels at a time with AVX2: every region of point_triangle_d2 is computed with the same
// operations in the same order (no FMA: the target does not enable it, so nothing is contracted), and the
// region is chosen by the same tests in the same priority, so each value is bit-identical to column_scalar's.
// Helpers of column_avx2 as macros or functions of the same target: lambdas would not inherit it.
#define TT_DOT(ux, uy, uz, vx, vy, vz) \
  _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(ux, vx), _mm256_mul_pd(uy, vy)), _mm256_mul_pd(uz, vz))
#define TT_LE(u, v) _mm256_cmp_pd(u, v, _CMP_LE_OQ)
#define TT_AND3(a, b, c) _mm256_and_pd(_mm256_and_pd(a, b), c)
#define TT_SEL(m, yes, no) _mm256_blendv_pd(no, yes, m)

// An edge region of point_triangle_d2 where its test `c` holds: |u - s v|^2 with s = num / den, or |u|^2 (u2) when
// den <= 0, into r; computed only when an active voxel is in the region (the divisions are the dearest part).
__attribute__((target("avx2"), always_inline)) inline __m256d edge_region(__m256d r, __m256d c, __m256d active,
                                                                          __m256d num, __m256d den, __m256d ux,
                                                                          __m256d uy, __m256d uz, __m256d vx,
                                                                          __m256d vy, __m256d vz, __m256d u2) {
  if (!_mm256_movemask_pd(_mm256_and_pd(c, active))) return r;
  const __m256d s = _mm256_div_pd(num, den);
  const __m256d wx = _mm256_sub_pd(ux, _mm256_mul_pd(s, vx)), wy = _mm256_sub_pd(uy, _mm256_mul_pd(s, vy)),
                wz = _mm256_sub_pd(uz, _mm256_mul_pd(s, vz));
  const __m256d e = TT_SEL(_mm256_cmp_pd(den, _mm256_setzero_pd(), _CMP_GT_OQ), TT_DOT(wx, wy, wz, wx, wy, wz), u2);
  return TT_SEL(c, e, r);
}

__attribute__((target("avx2"), always_inline)) inline void column_avx2(const TriangleFrame& t, double px, double py,
                                                                      double oz, int z0, int z1, double* row) {
  const __m256d zero = _mm256_setzero_pd();
  const __m256d abx = _mm256_set1_pd(t.ab.x()), aby = _mm256_set1_pd(t.ab.y()), abz = _mm256_set1_pd(t.ab.z());
  const __m256d acx = _mm256_set1_pd(t.ac.x()), acy = _mm256_set1_pd(t.ac.y()), acz = _mm256_set1_pd(t.ac.z());
  const __m256d bcx = _mm256_set1_pd(t.bc.x()), bcy = _mm256_set1_pd(t.bc.y()), bcz = _mm256_set1_pd(t.bc.z());
  const __m256d nx = _mm256_set1_pd(t.n.x()), ny = _mm256_set1_pd(t.n.y()), nz = _mm256_set1_pd(t.n.z());
  const __m256d apx = _mm256_set1_pd(px - t.A.x()), apy = _mm256_set1_pd(py - t.A.y());
  const __m256d bpx = _mm256_set1_pd(px - t.B.x()), bpy = _mm256_set1_pd(py - t.B.y());
  const __m256d cpx = _mm256_set1_pd(px - t.C.x()), cpy = _mm256_set1_pd(py - t.C.y());
  const __m256d Az = _mm256_set1_pd(t.A.z()), Bz = _mm256_set1_pd(t.B.z()), Cz = _mm256_set1_pd(t.C.z());
  const __m256d lane = _mm256_set_pd(3, 2, 1, 0);
  for (int z = z0; z <= z1; z += 4) {
    const __m256d in_range = _mm256_cmp_pd(lane, _mm256_set1_pd(double(z1 - z)), _CMP_LE_OQ);  // lanes z .. z1
    const __m256d cur = _mm256_maskload_pd(row + z, _mm256_castpd_si256(in_range));
    const __m256d pz = _mm256_add_pd(_mm256_set1_pd(oz + z), lane);
    const __m256d apz = _mm256_sub_pd(pz, Az);
    const __m256d hp = TT_DOT(nx, ny, nz, apx, apy, apz), hp2 = _mm256_mul_pd(hp, hp);
    __m256d active = _mm256_and_pd(in_range, _mm256_cmp_pd(hp2, cur, _CMP_LT_OQ));  // the plane test
    if (_mm256_movemask_pd(active) == 0) continue;
    const __m256d bpz = _mm256_sub_pd(pz, Bz), cpz = _mm256_sub_pd(pz, Cz);
    const __m256d d1 = TT_DOT(abx, aby, abz, apx, apy, apz), d2 = TT_DOT(acx, acy, acz, apx, apy, apz);
    const __m256d d3 = TT_DOT(abx, aby, abz, bpx, bpy, bpz), d4 = TT_DOT(acx, acy, acz, bpx, bpy, bpz);
    const __m256d d5 = TT_DOT(abx, aby, abz, cpx, cpy, cpz), d6 = TT_DOT(acx, acy, acz, cpx, cpy, cpz);
    const __m256d ap2 = TT_DOT(apx, apy, apz, apx, apy, apz), bp2 = TT_DOT(bpx, bpy, bpz, bpx, bpy, bpz),
                  cp2 = TT_DOT(cpx, cpy, cpz, cpx, cpy, cpz);
    const __m256d vc = _mm256_sub_pd(_mm256_mul_pd(d1, d4), _mm256_mul_pd(d3, d2));
    const __m256d vb = _mm256_sub_pd(_mm256_mul_pd(d5, d2), _mm256_mul_pd(d1, d6));
    const __m256d va = _mm256_sub_pd(_mm256_mul_pd(d3, d6), _mm256_mul_pd(d5, d4));
    const __m256d d43 = _mm256_sub_pd(d4, d3), d56 = _mm256_sub_pd(d5, d6);
    // The face region; a degenerate triangle there gives the nearest corner (equal minima are equal bits).
    __m256d r = t.has_normal ? hp2 : _mm256_min_pd(_mm256_min_pd(ap2, bp2), cp2);
    // The other regions from the last to the first, so that the first whose test holds wins, as in
    // point_triangle_d2.
    r = edge_region(r, TT_AND3(TT_LE(va, zero), TT_LE(zero, d43), TT_LE(zero, d56)), active, d43,
                    _mm256_add_pd(d43, d56), bpx, bpy, bpz, bcx, bcy, bcz, bp2);
    r = edge_region(r, TT_AND3(TT_LE(vb, zero), TT_LE(zero, d2), TT_LE(d6, zero)), active, d2, _mm256_sub_pd(d2, d6),
                    apx, apy, apz, acx, acy, acz, ap2);
    r = TT_SEL(_mm256_and_pd(TT_LE(zero, d6), TT_LE(d5, d6)), cp2, r);
    r = edge_region(r, TT_AND3(TT_LE(vc, zero), TT_LE(zero, d1), TT_LE(d3, zero)), active, d1, _mm256_sub_pd(d1, d3),
                    apx, apy, apz, abx, aby, abz, ap2);
    r = TT_SEL(_mm256_and_pd(TT_LE(zero, d3), TT_LE(d4, d3)), bp2, r);
    r = TT_SEL(_mm256_and_pd(TT_LE(d1, zero), TT_LE(d2, zero)), ap2, r);
    active = _mm256_and_pd(active, _mm256_cmp_pd(r, cur, _CMP_LT_OQ));  // strict, as in column_scalar
    _mm256_maskstore_pd(row + z, _mm256_castpd_si256(active), r);
  }
}
#undef TT_DOT
#undef TT_LE
#undef TT_AND3
#undef TT_SEL

// Every voxel of the block (d2: its 16^3 squared distances) in the triangle's widened ball and box.
void triangle_scalar(const TriangleFrame& t, const openvdb::Coord& org, double* d2) {
  for (int x = t.lo[0]; x <= t.hi[0]; ++x)
    for (int y = t.lo[1]; y <= t.hi[1]; ++y) {
      const double px = org[0] + x, py = org[1] + y;
      int z0, z1;
      if (column_range(t, px, py, org[2], z0, z1))
        column_scalar(t, px, py, org[2], z0, z1, d2 + ((x << kBlockLog) + y) * kBlock);
    }
}
__attribute__((target("avx2"))) void triangle_avx2(const TriangleFrame& t, const openvdb::Coord& org, double* d2) {
  for (int x = t.lo[0]; x <= t.hi[0]; ++x)
    for (int y = t.lo[1]; y <= t.hi[1]; ++y) {
      const double px = org[0] + x, py = org[1] + y;
      int z0, z1;
      if (column_range(t, px, py, org[2], z0, z1))
        column_avx2(t, px, py, org[2], z0, z1, d2 + ((x << kBlockLog) + y) * kBlock);
    }
}

bool cpu_has_avx2() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}

// A triangle crossing a lattice column (x, y): the height of the crossing and its weight on the winding
// number above it (+1 entering the inside, -1 leaving it).
struct Crossing {
  std::uint32_t column = 0;  // relative (x, y), packed
  double z = 0;
  std::int32_t weight = 0;
  bool operator<(const Crossing& o) const {
    return column != o.column ? column < o.column : z != o.z ? z < o.z : weight < o.weight;
  }
};

// Side of the column point q relative to the directed edge u -> v in the xy-plane, exactly (128-bit), with
// ties broken as if q were moved by (eps, eps^2) (simulation of simplicity): antisymmetric in (u, v), so the
// two triangles of an edge always disagree and every column crosses a closed mesh a balanced number of times.
int edge_side(const std::int64_t* u, const std::int64_t* v, std::int64_t qx, std::int64_t qy) {
  const I128 f = I128(v[0] - u[0]) * I128(qy - u[1]) - I128(v[1] - u[1]) * I128(qx - u[0]);
  if (f > 0) return 1;
  if (f < 0) return -1;
  if (v[1] != u[1]) return v[1] > u[1] ? -1 : 1;
  if (v[0] != u[0]) return v[0] > u[0] ? 1 : -1;
  return 0;
}

struct Setup {
  std::vector<Vec3> Q;                      // index-space positions
  std::vector<std::array<std::int64_t, 2>> F;  // fixed-point xy
  openvdb::Coord origin;                    // voxel origin of block (0, 0, 0)
  double hw = 0;
};

std::uint64_t block_key(int bx, int by, int bz) {
  return (std::uint64_t(bx) << (2 * kKeyBits)) | (std::uint64_t(by) << kKeyBits) | std::uint64_t(bz);
}

}  // namespace

bool narrow_band_fits(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles,
                      double voxel_size, double half_width_voxels) {
  if (triangles.empty()) return true;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& t : triangles)
    for (Index v : t) {
      if (v >= positions.size()) return false;
      lo = lo.cwiseMin(positions[v]);
      hi = hi.cwiseMax(positions[v]);
    }
  const double extent = (hi - lo).maxCoeff() / voxel_size;
  const double far = std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff()) / voxel_size;
  return extent + 2 * half_width_voxels < kNarrowBandMaxExtentVoxels && far < kMaxCoordinate / 2;
}

openvdb::FloatGrid::Ptr narrow_band_signed_distance(std::span<const Vec3> positions,
                                                    std::span<const std::array<Index, 3>> triangles,
                                                    const NarrowBandParams& params, NarrowBandReport* report) {
  ensure_openvdb_initialized();
  const double h = params.voxel_size, hw = params.half_width_voxels;
  auto xform = voxel_transform(h);
  check_signed_distance_input(positions, triangles, hw);
  const float background = float(hw * h);
  auto grid = openvdb::FloatGrid::create(background);
  grid->setTransform(xform);
  grid->setGridClass(openvdb::GRID_LEVEL_SET);
  NarrowBandReport rep;
  if (triangles.empty()) {
    if (report) *report = rep;
    return grid;
  }
  if (!narrow_band_fits(positions, triangles, h, hw))
    TT_THROW(InvalidInput, "signed distance: the mesh spans more than " << kNarrowBandMaxExtentVoxels
                                                                        << " voxels of " << h << " (narrow band)");

  // Index space, and the fixed-point copy of x and y for the exact column test.
  const auto t0 = Clock::now();
  const std::size_t nv = positions.size(), nt = triangles.size();
  Setup S;
  S.hw = hw;
  S.Q.resize(nv);
  S.F.resize(nv);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 8192), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      S.Q[i] = positions[i] / h;
      S.F[i] = {std::llround(S.Q[i].x() * kFixed), std::llround(S.Q[i].y() * kFixed)};
    }
  });
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& t : triangles)
    for (Index v : t) lo = lo.cwiseMin(S.Q[v]), hi = hi.cwiseMax(S.Q[v]);
  for (int a = 0; a < 3; ++a) S.origin[a] = floor_block(int(std::floor(lo[a] - hw)) - 1) * kBlock;

  // Voxel box of each triangle widened by the half width (voxels v with |v - triangle| < hw lie inside).
  auto voxel_box = [&](const std::array<Index, 3>& t, openvdb::Coord& b0, openvdb::Coord& b1) {
    for (int a = 0; a < 3; ++a) {
      const double mn = std::min({S.Q[t[0]][a], S.Q[t[1]][a], S.Q[t[2]][a]}),
                   mx = std::max({S.Q[t[0]][a], S.Q[t[1]][a], S.Q[t[2]][a]});
      b0[a] = int(std::ceil(mn - hw)) - S.origin[a];
      b1[a] = int(std::floor(mx + hw)) - S.origin[a];
    }
  };

  // (block, triangle) pairs, sorted: per block its triangles in increasing order.
  constexpr std::size_t kChunk = 4096;
  const std::size_t n_chunks = (nt + kChunk - 1) / kChunk;
  std::vector<std::vector<std::uint64_t>> chunk_pairs(n_chunks);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_chunks), [&](const auto& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) {
      auto& out = chunk_pairs[c];
      for (std::size_t f = c * kChunk, end = std::min(nt, (c + 1) * kChunk); f < end; ++f) {
        openvdb::Coord b0, b1;
        voxel_box(triangles[f], b0, b1);
        for (int x = floor_block(b0[0]); x <= floor_block(b1[0]); ++x)
          for (int y = floor_block(b0[1]); y <= floor_block(b1[1]); ++y)
            for (int z = floor_block(b0[2]); z <= floor_block(b1[2]); ++z)
              out.push_back((block_key(x, y, z) << 32) | std::uint64_t(f));
      }
    }
  });
  std::vector<std::uint64_t> pairs;
  {
    std::size_t n = 0;
    for (const auto& c : chunk_pairs) n += c.size();
    pairs.reserve(n);
    for (auto& c : chunk_pairs) {
      pairs.insert(pairs.end(), c.begin(), c.end());
      std::vector<std::uint64_t>().swap(c);
    }
  }
  {
    const std::unique_ptr<std::uint64_t[]> scratch(new std::uint64_t[pairs.size()]);  // left unwritten
    radix_sort(pairs, {scratch.get(), pairs.size()});
  }
  std::vector<std::size_t> block_begin;
  for (std::size_t i = 0; i < pairs.size(); ++i)
    if (i == 0 || (pairs[i] >> 32) != (pairs[i - 1] >> 32)) block_begin.push_back(i);
  block_begin.push_back(pairs.size());
  const std::size_t n_blocks = block_begin.size() - 1;
  rep.blocks = n_blocks;
  rep.triangle_blocks = pairs.size();
  rep.seconds_bin = since(t0);

  // Signed crossings of the lattice columns, sorted by column and height.
  const auto t1 = Clock::now();
  std::vector<std::vector<Crossing>> chunk_crossings(n_chunks);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_chunks), [&](const auto& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) {
      auto& out = chunk_crossings[c];
      for (std::size_t f = c * kChunk, end = std::min(nt, (c + 1) * kChunk); f < end; ++f) {
        const auto& t = triangles[f];
        const std::int64_t* p[3] = {S.F[t[0]].data(), S.F[t[1]].data(), S.F[t[2]].data()};
        const std::int64_t unit = std::int64_t(kFixed);
        std::int64_t x0 = std::min({p[0][0], p[1][0], p[2][0]}), x1 = std::max({p[0][0], p[1][0], p[2][0]});
        std::int64_t y0 = std::min({p[0][1], p[1][1], p[2][1]}), y1 = std::max({p[0][1], p[1][1], p[2][1]});
        // Columns in the closed box (a column on the box boundary can still be inside by the tie rule).
        for (std::int64_t X = -floor_div(-x0, unit); X <= floor_div(x1, unit); ++X)
          for (std::int64_t Y = -floor_div(-y0, unit); Y <= floor_div(y1, unit); ++Y) {
            const std::int64_t qx = X * unit, qy = Y * unit;
            const int s0 = edge_side(p[1], p[2], qx, qy), s1 = edge_side(p[2], p[0], qx, qy),
                      s2 = edge_side(p[0], p[1], qx, qy);
            if (s0 == 0 || s0 != s1 || s1 != s2) continue;
            // Barycentric weights of the crossing from the same edge functions (as doubles).
            const auto ef = [&](const std::int64_t* u, const std::int64_t* v) {
              return double(I128(v[0] - u[0]) * I128(qy - u[1]) - I128(v[1] - u[1]) * I128(qx - u[0]));
            };
            const double w0 = ef(p[1], p[2]), w1 = ef(p[2], p[0]), w2 = ef(p[0], p[1]), sum = w0 + w1 + w2;
            const double z = sum != 0 ? (w0 * S.Q[t[0]].z() + w1 * S.Q[t[1]].z() + w2 * S.Q[t[2]].z()) / sum
                                      : (S.Q[t[0]].z() + S.Q[t[1]].z() + S.Q[t[2]].z()) / 3;
            const std::int64_t cx = X - S.origin[0], cy = Y - S.origin[1];
            // Counter-clockwise seen from +z (normal up): going up the column leaves the inside.
            out.push_back(Crossing{std::uint32_t((cx << 16) | cy), z, -s0});
          }
      }
    }
  });
  std::vector<Crossing> crossings;
  {
    std::size_t n = 0;
    for (const auto& c : chunk_crossings) n += c.size();
    crossings.reserve(n);
    for (auto& c : chunk_crossings) {
      crossings.insert(crossings.end(), c.begin(), c.end());
      std::vector<Crossing>().swap(c);
    }
  }
  tbb::parallel_sort(crossings.begin(), crossings.end());
  rep.crossings = crossings.size();
  for (std::size_t i = 0; i < crossings.size();) {
    std::size_t j = i;
    int sum = 0;
    while (j < crossings.size() && crossings[j].column == crossings[i].column) sum += crossings[j++].weight;
    rep.unbalanced_columns += sum != 0;
    i = j;
  }
  rep.seconds_crossings = since(t1);

  // Per block: exact minimum distance over its triangles, the winding number, the leaf nodes.
  const auto t2 = Clock::now();
  using Leaf = openvdb::FloatTree::LeafNodeType;
  std::vector<std::array<Leaf*, 8>> block_leaves(n_blocks);
  std::vector<std::size_t> block_active(n_blocks, 0);
  const double hw2 = hw * hw;
  const bool simd = params.vectorized && cpu_has_avx2();
  rep.vectorized = simd;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_blocks, 1), [&](const auto& r) {
    std::vector<double> d2(kBlockVoxels + 4);  // padded: the AVX2 loop reads (masked) up to 3 past a column
    std::vector<std::int32_t> winding(kBlockVoxels);
    for (std::size_t b = r.begin(); b != r.end(); ++b) {
      const std::uint64_t key = pairs[block_begin[b]] >> 32;
      const std::uint64_t mask = (std::uint64_t(1) << kKeyBits) - 1;
      const openvdb::Coord rel(int((key >> (2 * kKeyBits)) & mask) * kBlock, int((key >> kKeyBits) & mask) * kBlock,
                               int(key & mask) * kBlock);
      const openvdb::Coord org = rel + S.origin;
      std::fill(d2.begin(), d2.end(), hw2);
      for (std::size_t k = block_begin[b]; k < block_begin[b + 1]; ++k) {
        const auto& t = triangles[pairs[k] & 0xffffffffu];
        openvdb::Coord b0, b1;
        voxel_box(t, b0, b1);
        TriangleFrame tf;
        tf.A = S.Q[t[0]], tf.B = S.Q[t[1]], tf.C = S.Q[t[2]];
        const Vec3 &A = tf.A, &B = tf.B, &C = tf.C;
        Vec3 n = (B - A).cross(C - A);
        const double len = n.norm();
        n = len > 0 ? Vec3(n / len) : Vec3::Zero();
        tf.n = n;
        tf.ab = B - A, tf.ac = C - A, tf.bc = C - B;
        tf.has_normal = n.squaredNorm() > 0;
        for (int a = 0; a < 3; ++a) {
          tf.lo[a] = std::max(b0[a] - rel[a], 0);
          tf.hi[a] = std::min(b1[a] - rel[a], kBlock - 1);
        }
        // Only voxels within the half width of the triangle's bounding ball (about half of its box).
        tf.centre = (A + B + C) / 3;
        const Vec3& centre = tf.centre;
        const double rt = std::sqrt(std::max({(A - centre).squaredNorm(), (B - centre).squaredNorm(),
                                              (C - centre).squaredNorm()}));
        const double R = rt + hw;
        tf.R2 = R * R;
        if (simd) triangle_avx2(tf, org, d2.data());
        else triangle_scalar(tf, org, d2.data());
      }
      // Winding number of every voxel of the block from the crossings of its columns.
      for (int x = 0; x < kBlock; ++x)
        for (int y = 0; y < kBlock; ++y) {
          const std::uint32_t col = std::uint32_t(((rel[0] + x) << 16) | (rel[1] + y));
          auto it = std::lower_bound(crossings.begin(), crossings.end(), col,
                                     [](const Crossing& c, std::uint32_t k) { return c.column < k; });
          int w = 0;
          std::int32_t* out = winding.data() + ((x << kBlockLog) + y) * kBlock;
          for (int z = 0; z < kBlock; ++z) {
            const double zz = org[2] + z;
            while (it != crossings.end() && it->column == col && it->z < zz) w += (it++)->weight;
            out[z] = w;
          }
        }
      std::array<Leaf*, 8> leaves{};
      std::size_t active = 0;
      for (int l = 0; l < 8; ++l) {
        const int lx = (l >> 2) & 1, ly = (l >> 1) & 1, lz = l & 1;
        Leaf* leaf = nullptr;
        for (int x = 0; x < 8; ++x)
          for (int y = 0; y < 8; ++y)
            for (int z = 0; z < 8; ++z) {
              const int i = (((lx * 8 + x) << kBlockLog) + ly * 8 + y) * kBlock + lz * 8 + z;
              if (!(d2[i] < hw2)) continue;
              if (!leaf) leaf = new Leaf(org.offsetBy(lx * 8, ly * 8, lz * 8), background, false);
              const float d = float(std::sqrt(d2[i]) * h);
              leaf->setValueOn(Leaf::coordToOffset(openvdb::Coord(x, y, z)), winding[i] >= 1 ? -d : d);
              ++active;
            }
        if (!leaf) continue;
        for (int x = 0; x < 8; ++x)
          for (int y = 0; y < 8; ++y)
            for (int z = 0; z < 8; ++z) {
              const openvdb::Index o = Leaf::coordToOffset(openvdb::Coord(x, y, z));
              if (leaf->isValueOn(o)) continue;
              const int i = (((lx * 8 + x) << kBlockLog) + ly * 8 + y) * kBlock + lz * 8 + z;
              leaf->setValueOnly(o, winding[i] >= 1 ? -background : background);
            }
        leaves[l] = leaf;
      }
      block_leaves[b] = leaves;
      block_active[b] = active;
    }
  });
  rep.seconds_blocks = since(t2);

  const auto t3 = Clock::now();
  auto& tree = grid->tree();
  for (std::size_t b = 0; b < n_blocks; ++b) {
    for (Leaf* leaf : block_leaves[b])
      if (leaf) tree.addLeaf(leaf);
    rep.active_voxels += block_active[b];
  }
  // The leaves hold exact signs; the tiles between them take the sign of their neighbours (minLevel 1).
  openvdb::tools::signedFloodFill(tree, /*threaded=*/true, /*grainSize=*/1, /*minLevel=*/1);
  rep.seconds_tree = since(t3);
  if (report) *report = rep;
  return grid;
}

}  // namespace topotrack
