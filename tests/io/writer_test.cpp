// Round trips of the PLY and OBJ writers through the readers, and the writers' input checks.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "io/error.hpp"
#include "io/mesh_reader.hpp"
#include "io/obj_reader.hpp"
#include "io/obj_writer.hpp"
#include "io/ply_reader.hpp"
#include "io/ply_writer.hpp"
#include "tests/io/sample_meshes.hpp"
#include "tests/io/temp_dir.hpp"

namespace topotrack {
namespace {

using test::attributed_octahedron;
using test::octahedron;
using test::TempDir;

// Positions equal as floats (ascii float output is the shortest decimal of the float), or exactly with double
// positions.
void expect_same(const MeshData& a, const MeshData& b, bool exact_positions) {
  ASSERT_EQ(a.vertex_count(), b.vertex_count());
  ASSERT_EQ(a.triangles, b.triangles);
  for (std::size_t v = 0; v < a.vertex_count(); ++v)
    for (int c = 0; c < 3; ++c) {
      if (exact_positions)
        EXPECT_EQ(b.positions[v][c], a.positions[v][c]) << "vertex " << v << " axis " << c;
      else
        EXPECT_EQ(static_cast<float>(b.positions[v][c]), static_cast<float>(a.positions[v][c]))
            << "vertex " << v;
    }
  EXPECT_EQ(a.ids, b.ids);
  ASSERT_EQ(a.attributes.size(), b.attributes.size());
  for (std::size_t k = 0; k < a.attributes.size(); ++k) {
    const VertexAttribute& x = a.attributes[k];
    const VertexAttribute& y = b.attributes[k];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.width, y.width);
    ASSERT_EQ(x.values.size(), y.values.size()) << x.name;
    const float tol = x.name == "color" ? 0.5f / 255.0f + 1e-6f : 0.0f;
    for (std::size_t i = 0; i < x.values.size(); ++i)
      EXPECT_NEAR(x.values[i], y.values[i], tol) << x.name << "[" << i << "]";
  }
}

struct Encoding {
  const char* name;
  PlyWriteOptions options;
};

class PlyRoundTrip : public ::testing::TestWithParam<Encoding> {};

TEST_P(PlyRoundTrip, AttributedMesh) {
  const MeshData m = attributed_octahedron();
  const PlyWriteOptions o = GetParam().options;
  const std::string bytes = encode_ply(m, o);
  const std::string fmt = o.ascii        ? "format ascii 1.0"
                          : o.big_endian ? "format binary_big_endian 1.0"
                                         : "format binary_little_endian 1.0";
  EXPECT_NE(bytes.find(fmt), std::string::npos);
  expect_same(m, parse_ply(bytes, "mem.ply"), o.double_positions);
}

TEST_P(PlyRoundTrip, ThroughFile) {
  TempDir dir;
  const MeshData m = test::uv_sphere(40, 60);
  const auto path = dir / "sphere.ply";
  write_ply(path, m, GetParam().options);
  expect_same(m, read_ply(path), GetParam().options.double_positions);
  expect_same(m, read_mesh(path), GetParam().options.double_positions);
}

TEST_P(PlyRoundTrip, LargeIdsUseInt64) {
  MeshData m = octahedron();
  m.ids =
      std::vector<std::int64_t>{0, 1, std::int64_t{1} << 40, -5, std::numeric_limits<std::int64_t>::max(), 2};
  const std::string bytes = encode_ply(m, GetParam().options);
  EXPECT_NE(bytes.find("property int64 id"), std::string::npos);
  expect_same(m, parse_ply(bytes, "mem.ply"), GetParam().options.double_positions);
}

INSTANTIATE_TEST_SUITE_P(Encodings, PlyRoundTrip,
                         ::testing::Values(Encoding{"binary_le", {}},
                                           Encoding{"binary_be", {false, false, true}},
                                           Encoding{"ascii", {true, false, false}},
                                           Encoding{"binary_le_double", {false, true, false}},
                                           Encoding{"binary_be_double", {false, true, true}},
                                           Encoding{"ascii_double", {true, true, false}}),
                         [](const auto& p) { return std::string(p.param.name); });

TEST(PlyWriter, DefaultIsBinaryLittleEndianFloat) {
  const std::string bytes = encode_ply(octahedron());
  EXPECT_EQ(bytes.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
  EXPECT_NE(bytes.find("property float x\n"), std::string::npos);
  EXPECT_NE(bytes.find("property list uchar int vertex_indices\n"), std::string::npos);
  EXPECT_EQ(bytes.find("property int id"), std::string::npos);
  const std::size_t body = bytes.find("end_header\n") + 11;
  EXPECT_EQ(bytes.size() - body, 6 * 12 + 8 * 13u);
}

TEST(PlyWriter, PropertyNamesFollowTheConventions) {
  const std::string h = encode_ply(attributed_octahedron(), {true});
  for (const char* p :
       {"property int id\n", "property uchar red\n", "property uchar green\n", "property uchar blue\n",
        "property float vx\n", "property float vz\n", "property float nx\n", "property float curvature\n",
        "property float uv_0\n", "property float uv_1\n", "property float paint\n"})
    EXPECT_NE(h.find(p), std::string::npos) << p;
}

TEST(PlyWriter, RgbaColour) {
  MeshData m = octahedron();
  VertexAttribute c{"color", 4, {}};
  for (std::size_t i = 0; i < 6 * 4; ++i) c.values.push_back(static_cast<float>(i % 5) / 4.0f);
  m.attributes = {c};
  expect_same(m, parse_ply(encode_ply(m), "rgba.ply"), false);
}

TEST(PlyWriter, RejectsBadInput) {
  MeshData m = octahedron();
  m.attributes = {{"s", 1, {1, 2, 3}}};
  EXPECT_THROW(encode_ply(m), InvalidInput);
  m = octahedron();
  m.triangles[3][1] = 6;
  EXPECT_THROW(encode_ply(m), InvalidInput);
  m.triangles[3][1] = -1;
  EXPECT_THROW(encode_ply(m), InvalidInput);
  m = octahedron();
  m.positions[2][1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(encode_ply(m), InvalidInput);
  m = octahedron();
  m.positions[2][1] = 1e300;
  EXPECT_THROW(encode_ply(m), InvalidInput);
  EXPECT_NO_THROW(encode_ply(m, {false, true}));
  m = octahedron();
  m.attributes = {{"bad name", 1, std::vector<float>(6, 0.f)}};
  EXPECT_THROW(encode_ply(m), InvalidInput);
  m.attributes = {{"x", 1, std::vector<float>(6, 0.f)}};
  EXPECT_THROW(encode_ply(m), InvalidInput);
  m.attributes = {{"color", 3, std::vector<float>(18, std::numeric_limits<float>::infinity())}};
  EXPECT_THROW(encode_ply(m), InvalidInput);
  m = octahedron();
  m.ids = std::vector<std::int64_t>{1, 2};
  EXPECT_THROW(encode_ply(m), InvalidInput);
}

TEST(PlyWriter, EmptyFaceListRoundTrips) {
  MeshData m = octahedron();
  m.triangles.clear();
  expect_same(m, parse_ply(encode_ply(m), "points.ply"), false);
}

TEST(ObjWriter, RoundTripIsExact) {
  const MeshData m = attributed_octahedron();
  const MeshData back = parse_obj(encode_obj(m), "mem.obj");
  EXPECT_EQ(back.positions, m.positions);
  EXPECT_EQ(back.triangles, m.triangles);
  EXPECT_FALSE(back.ids.has_value());
  EXPECT_TRUE(back.attributes.empty());
}

TEST(ObjWriter, ThroughFile) {
  TempDir dir;
  const MeshData m = test::uv_sphere(30, 50);
  write_obj(dir / "s.obj", m);
  const MeshData back = read_obj(dir / "s.obj");
  EXPECT_EQ(back.positions, m.positions);
  EXPECT_EQ(back.triangles, m.triangles);
}

TEST(ObjWriter, RejectsBadInput) {
  MeshData m = octahedron();
  m.positions[0][0] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(encode_obj(m), InvalidInput);
  m = octahedron();
  m.triangles[0][0] = 99;
  EXPECT_THROW(encode_obj(m), InvalidInput);
}

TEST(WriteMesh, ChoosesByExtension) {
  TempDir dir;
  const MeshData m = attributed_octahedron();
  write_mesh(dir / "a.PLY", m);
  write_mesh(dir / "a.obj", m);
  EXPECT_EQ(test::read_all(dir / "a.PLY").rfind("ply\nformat binary_little_endian", 0), 0u);
  expect_same(m, read_mesh(dir / "a.PLY"), false);
  EXPECT_EQ(read_mesh(dir / "a.obj").positions, m.positions);
  EXPECT_THROW(write_mesh(dir / "a.stl", m), InvalidInput);
  EXPECT_FALSE(std::filesystem::exists(dir / "a.stl"));
}

TEST(WriteMesh, ErrorsNameThePath) {
  TempDir dir;
  const auto missing = dir / "no" / "such" / "folder" / "x.ply";
  try {
    write_ply(missing, octahedron());
    FAIL() << "no exception";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(missing.string()), std::string::npos) << e.what();
  }
  MeshData bad = octahedron();
  bad.triangles[0][0] = 42;
  try {
    write_obj(dir / "bad.obj", bad);
    FAIL() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("bad.obj"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace topotrack
