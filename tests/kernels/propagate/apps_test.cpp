// Tests of what the §5 applications carry along a sequence: pattern sources, image projection, propagation
// round trip (§4.6), the PC2 point cache, connectivity matching, frame geometry from MeshData.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>

#include "io/error.hpp"
#include "io/mapped_file.hpp"
#include "io/mesh_data.hpp"
#include "io/ply_writer.hpp"
#include "kernels/improve/improve.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/propagate/propagate.hpp"
#include "kernels/propagate/frame_geometry.hpp"
#include "kernels/propagate/image_projection.hpp"
#include "kernels/propagate/patterns.hpp"
#include "io/pc2.hpp"
#include "kernels/propagate/tracked_sequence.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

double smooth_field(const Vec3& p) { return std::sin(2 * p.x()) + std::cos(3 * p.y()) + 0.5 * p.z(); }

TEST(Patterns, CheckerStripesSineConstant) {
  const std::vector<Vec3> pts = {Vec3(0.1, 0.1, 0.1), Vec3(1.1, 0.1, 0.1), Vec3(1.1, 1.1, 0.1), Vec3(-0.1, 0.1, 0.1)};
  PatternParams p;
  p.cell = 1;
  p.a = {1, 0, 0};
  p.b = {0, 0, 1};
  const auto checker = evaluate_pattern(pts, p);
  ASSERT_EQ(checker.size(), 12u);
  EXPECT_EQ(checker[0], 1);   // cell (0,0,0): a
  EXPECT_EQ(checker[5], 1);   // cell (1,0,0): b
  EXPECT_EQ(checker[6], 1);   // cell (1,1,0): a
  EXPECT_EQ(checker[11], 1);  // cell (-1,0,0): b
  p.kind = PatternKind::Stripes;
  p.a = {0};
  p.b = {2};
  const auto stripes = evaluate_pattern(pts, p);
  EXPECT_EQ(stripes, (std::vector<float>{0, 2, 2, 2}));
  p.kind = PatternKind::Sine;
  p.cell = 2;
  const auto sine = evaluate_pattern(pts, p);
  EXPECT_NEAR(sine[0], 1 + std::sin(M_PI * 0.1 / 2), 1e-6);
  p.kind = PatternKind::Constant;
  EXPECT_EQ(evaluate_pattern(pts, p), (std::vector<float>{0, 0, 0, 0}));
  p.b = {1, 2};
  EXPECT_THROW(evaluate_pattern(pts, p), InvalidInput);
  EXPECT_EQ(parse_pattern_kind("stripes"), PatternKind::Stripes);
  EXPECT_THROW(parse_pattern_kind("plaid"), InvalidInput);
  EXPECT_EQ(blend_fields(std::vector<float>{0, 2}, std::vector<float>{4, 4}, 0.25), (std::vector<float>{1, 2.5}));
  EXPECT_THROW(blend_fields(std::vector<float>{0}, std::vector<float>{4, 4}, 0.5), InvalidInput);
}

TEST(Patterns, ImageProjection) {
  // Left half red, right half green, seen from +z.
  Image im(64, 32);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 64; ++x) im.pixel(x, y)[x < 32 ? 0 : 1] = 255;
  Camera cam;
  cam.eye = Vec3(0, 0, 10);
  const std::vector<Vec3> pts = {Vec3(-1, 0, 0), Vec3(1, 0.3, 0), Vec3(100, 0, 0), Vec3(0, 0, 20)};
  const float grey[3] = {0.5f, 0.5f, 0.5f};
  std::size_t outside = 0;
  const auto c = project_image(pts, im, cam, grey, &outside);
  EXPECT_EQ(outside, 2u);
  EXPECT_FLOAT_EQ(c[0], 1.0f);
  EXPECT_FLOAT_EQ(c[1], 0.0f);
  EXPECT_FLOAT_EQ(c[3], 0.0f);
  EXPECT_FLOAT_EQ(c[4], 1.0f);
  EXPECT_FLOAT_EQ(c[6], 0.5f);
  EXPECT_FLOAT_EQ(c[9], 0.5f);
  EXPECT_THROW(project_image(pts, Image(), cam, grey), InvalidInput);
}

// §4.6: a smooth field carried forward through real re-sampling events (splits, then collapses) and back.
TEST(Propagation, ForwardBackwardRoundTripOfSmoothField) {
  test::Soup s = test::icosphere(4);
  test::jitter(s, 0.005, 11);
  SurfaceMesh mesh = s.mesh();
  IdField start;
  start.width = 1;
  for (Vertex v(0); v.idx < mesh.vertices_size(); v = Vertex(v.idx + 1)) {
    start.ids.push_back(mesh.id(v));
    start.values.push_back(float(smooth_field(mesh.position(v))));
  }
  EventList events;
  const double L = mean_edge_length(mesh);
  ImproveParams fine;
  fine.target_edge_length = 0.5 * L;
  const ImproveReport r1 = improve_mesh(mesh, fine, &events);
  ASSERT_GT(r1.splits, 100u);
  {
    // Splits alone have no backward rules: the round trip is exact on the original vertices.
    const IdField back = propagate_backward(events, propagate_forward(events, start));
    std::vector<float> round;
    const float nan[1] = {std::nanf("")};
    ASSERT_EQ(gather_values(back, start.ids, nan, round), 0u);
    ASSERT_EQ(r1.collapses, 0u);
    EXPECT_EQ(round, start.values);
  }
  std::printf("[ propagate ] after refinement: %zu vertices\n", mesh.n_vertices());
  ImproveParams coarse;
  coarse.target_edge_length = 1.5 * L;
  const ImproveReport r2 = improve_mesh(mesh, coarse, &events);
  ASSERT_GT(r2.collapses, 100u);

  PropagateReport fr;
  const IdField forward = propagate_forward(events, start, &fr);
  EXPECT_EQ(fr.targets_missing, 0u);
  // Every vertex of the re-sampled mesh has a value close to the field at its position.
  std::vector<float> values;
  const float nan[1] = {std::nanf("")};
  ASSERT_EQ(gather_values(forward, mesh.ids(), nan, values), 0u);
  double fwd_max = 0;
  for (Vertex v(0); v.idx < mesh.vertices_size(); v = Vertex(v.idx + 1))
    fwd_max = std::max(fwd_max, std::abs(values[v.idx] - smooth_field(mesh.position(v))));

  const IdField back = propagate_backward(events, forward);
  std::vector<float> round;
  ASSERT_EQ(gather_values(back, start.ids, nan, round), 0u);
  double max_err = 0, sum = 0;
  for (std::size_t i = 0; i < round.size(); ++i) {
    const double e = std::abs(round[i] - start.values[i]);
    max_err = std::max(max_err, e);
    sum += e;
  }
  const double mean_err = sum / round.size();
  std::printf("[ propagate ] %zu events; field range ~4; forward error max %.4f; round trip error max %.4f mean %.5f\n",
              events.size(), fwd_max, max_err, mean_err);
  // Forward rules interpolate (error of linear interpolation); backward collapse rules give both ends the
  // kept vertex's value, so the round trip error is bounded by the gradient (|grad f| <= 3.7) times the
  // distance a value travels through chained collapses (a few edge lengths).
  const double grad_l = 3.7 * L;
  EXPECT_LT(fwd_max, 0.2 * grad_l);
  EXPECT_LT(max_err, 2.0 * grad_l);
  EXPECT_LT(mean_err, 0.25 * grad_l);
}

// §4.6 round trip over a sequence: frame 0 {0, 1, 2} -> frame 1 by a split of 0-1 and a collapse of 1-2.
TEST(Propagation, SequenceRoundTripReport) {
  std::vector<EventList> events(3);
  events[1].record_split(0, 1, 3, 0.5);
  events[1].record_collapse(1, 2, 4);
  IdField start;
  start.ids = {0, 1, 2};
  start.values = {0, 1, 4};
  auto events_of = [&](std::size_t k) { return events.at(k); };
  const RoundTripReport r = round_trip(2, 0, start, events_of);
  EXPECT_EQ(r.values, 3u);
  EXPECT_EQ(r.missing, 0u);
  EXPECT_DOUBLE_EQ(r.range, 4);
  // Forward 4 <- (1 + 4) / 2; backward both ends of the collapse take 2.5; vertex 0 is untouched.
  EXPECT_DOUBLE_EQ(r.max_abs, 1.5);
  EXPECT_DOUBLE_EQ(r.mean_abs, 1.0);
  EXPECT_DOUBLE_EQ(r.rms, std::sqrt(1.5));
  // From the last frame the round trip is empty (nothing to carry): exact.
  IdField end;
  end.ids = {0, 3, 4};
  end.values = {1, 2, 3};
  EXPECT_EQ(round_trip(2, 1, end, events_of).max_abs, 0);
  // Frame 2 has no events: the same result through one more frame.
  EXPECT_DOUBLE_EQ(round_trip(3, 0, start, events_of).mean_abs, 1.0);
  EXPECT_THROW(round_trip(2, 2, start, events_of), InvalidInput);
}

// Reading frames: the file is named in every error; a frame without ids is rejected where ids are needed.
TEST(FrameGeometry, LoadFrame) {
  const auto dir = std::filesystem::temp_directory_path() / "topotrack_load_frame_test";
  std::filesystem::create_directories(dir);
  MeshData d;
  d.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  d.triangles = {{0, 1, 2}};
  write_ply(dir / "plain.ply", d);
  d.ids = std::vector<std::int64_t>{5, 6, 7};
  write_ply(dir / "tracked.ply", d);
  EXPECT_EQ(read_frame_file(dir / "tracked.ply", true).geometry.ids, (std::vector<VertexId>{5, 6, 7}));
  EXPECT_TRUE(read_frame_file(dir / "plain.ply", false).geometry.ids.empty());
  try {
    read_frame_file(dir / "plain.ply", true);
    ADD_FAILURE() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("plain.ply: no vertex ids"), std::string::npos) << e.what();
  }
  d.ids = std::vector<std::int64_t>{5, 5, 7};
  write_ply(dir / "repeated.ply", d);
  try {
    read_frame_file(dir / "repeated.ply", true);
    ADD_FAILURE() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("repeated.ply: vertex id 5 appears twice"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_frame_file(dir / "missing.ply", true), Error);
  std::filesystem::remove_all(dir);
}

TEST(Pc2, FileLayoutReadsBack) {
  const auto dir = std::filesystem::temp_directory_path() / "topotrack_pc2_test";
  std::filesystem::create_directories(dir);
  const auto path = dir / "cache.pc2";
  const Pc2Header h{.points = 3, .start_frame = 5, .sample_rate = 1, .samples = 2};
  {
    Pc2Writer w(path, h);
    const std::vector<std::array<double, 3>> a = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}};
    const std::vector<std::array<double, 3>> b = {{-1, -2, -3}, {0.5, 0.25, 0.125}, {9, 9, 9}};
    w.add_sample(a);
    EXPECT_THROW(w.add_sample(std::vector<std::array<double, 3>>(2)), InvalidInput);
    w.add_sample(b);
    EXPECT_THROW(w.add_sample(a), InvalidInput);
    w.commit();
  }
  // Raw layout.
  const MappedFile raw(path);
  ASSERT_EQ(raw.size(), 32u + 2 * 3 * 3 * 4);
  EXPECT_EQ(std::memcmp(raw.data(), "POINTCACHE2\0", 12), 0);
  std::int32_t version, points, samples;
  float start, rate, x;
  std::memcpy(&version, raw.data() + 12, 4);
  std::memcpy(&points, raw.data() + 16, 4);
  std::memcpy(&start, raw.data() + 20, 4);
  std::memcpy(&rate, raw.data() + 24, 4);
  std::memcpy(&samples, raw.data() + 28, 4);
  std::memcpy(&x, raw.data() + 32 + 9 * 4 + 3 * 4, 4);
  EXPECT_EQ(version, 1);
  EXPECT_EQ(points, 3);
  EXPECT_EQ(start, 5.0f);
  EXPECT_EQ(rate, 1.0f);
  EXPECT_EQ(samples, 2);
  EXPECT_EQ(x, 0.5f);
  const Pc2Data d = read_pc2(path);
  EXPECT_EQ(d.header.points, 3);
  EXPECT_EQ(d.header.samples, 2);
  EXPECT_EQ(d.sample(1)[8], 9.0f);
  EXPECT_EQ(d.sample(0)[4], 4.0f);
  // Corrupt variants.
  const std::string bytes(raw.data(), raw.size());
  EXPECT_THROW(decode_pc2(bytes.substr(0, 40), "cut"), InvalidInput);
  std::string bad = bytes;
  bad[0] = 'X';
  EXPECT_THROW(decode_pc2(bad, "magic"), InvalidInput);
  bad = bytes;
  bad[12] = 2;
  EXPECT_THROW(decode_pc2(bad, "version"), InvalidInput);
  EXPECT_THROW(read_pc2(dir / "missing.pc2"), IoError);
  // Fewer samples than announced: nothing is left behind.
  {
    Pc2Writer w(dir / "short.pc2", h);
    EXPECT_THROW(w.commit(), InvalidInput);
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "short.pc2"));
  EXPECT_THROW(Pc2Writer(dir / "zero.pc2", Pc2Header{}), InvalidInput);
  std::filesystem::remove_all(dir);
}

TEST(Pc2, MatchConnectivity) {
  const test::Soup s = test::icosphere(1);
  std::vector<VertexId> ids(s.positions.size());
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = 100 + i;
  // Same ids in the same order, triangles rotated and reordered.
  std::vector<std::array<Index, 3>> t2(s.triangles.rbegin(), s.triangles.rend());
  for (auto& t : t2) t = {t[1], t[2], t[0]};
  auto m = match_connectivity(ids, s.triangles, ids, t2);
  ASSERT_TRUE(m);
  EXPECT_EQ((*m)[5], 5u);
  // Vertices permuted (swap 0 and 1) in frame b.
  std::vector<VertexId> ids_b = ids;
  std::swap(ids_b[0], ids_b[1]);
  std::vector<std::array<Index, 3>> tb = s.triangles;
  for (auto& t : tb)
    for (Index& v : t) v = v == 0 ? 1 : v == 1 ? 0 : v;
  m = match_connectivity(ids, s.triangles, ids_b, tb);
  ASSERT_TRUE(m);
  EXPECT_EQ((*m)[0], 1u);
  EXPECT_EQ((*m)[1], 0u);
  // A flipped triangle orientation or a different id is a different connectivity.
  std::vector<std::array<Index, 3>> flipped = s.triangles;
  std::swap(flipped[0][1], flipped[0][2]);
  EXPECT_FALSE(match_connectivity(ids, s.triangles, ids, flipped));
  ids_b = ids;
  ids_b[3] = 7;
  EXPECT_FALSE(match_connectivity(ids, s.triangles, ids_b, s.triangles));
  EXPECT_TRUE(match_connectivity({}, s.triangles, {}, t2));
}

TEST(FrameGeometry, FromMeshData) {
  MeshData d;
  d.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  d.triangles = {{0, 1, 2}};
  d.ids = std::vector<std::int64_t>{7, 3, 9};
  d.attributes.push_back({"color", 4, {1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 1}});
  const FrameGeometry g = frame_geometry(d);
  EXPECT_EQ(g.ids, (std::vector<VertexId>{7, 3, 9}));
  set_positions(d, std::vector<Vec3>{Vec3(1, 2, 3), Vec3(0, 0, 0), Vec3(0, 1, 0)});
  EXPECT_EQ(d.positions[0][2], 3.0);
  EXPECT_THROW(set_positions(d, std::vector<Vec3>(2)), InvalidInput);
  set_attribute(d, "height", 1, {1, 2, 3});
  set_attribute(d, "height", 1, {4, 5, 6});
  EXPECT_EQ(d.attribute("height")->values[2], 6.0f);
  EXPECT_THROW(set_attribute(d, "x", 2, {1, 2}), InvalidInput);
  MeshData bad = d;
  bad.triangles[0][2] = 3;
  EXPECT_THROW(frame_geometry(bad), InvalidInput);
  bad = d;
  (*bad.ids)[1] = 7;
  EXPECT_THROW(frame_geometry(bad), InvalidInput);
}

}  // namespace
}  // namespace topotrack
