// The PLY and OBJ readers on hand-written inputs: encodings, property types, polygons, skipped elements, and
// the rejection of malformed input with the file and the position in the message.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cstring>

#include "io/error.hpp"
#include "io/mapped_file.hpp"
#include "io/mesh_reader.hpp"
#include "io/obj_reader.hpp"
#include "io/ply_reader.hpp"
#include "tests/io/temp_dir.hpp"

namespace topotrack {
namespace {

const std::string kAsciiQuad =
    "ply\nformat ascii 1.0\ncomment a quad and a triangle\nelement vertex 5\nproperty float x\nproperty "
    "float y\n"
    "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face 2\n"
    "property list uchar int vertex_indices\nelement edge 1\nproperty int vertex1\nproperty int "
    "vertex2\nend_header\n"
    "0 0 0 255 0 0\n1 0 0 0 255 0\n1 1 0 0 0 255\n0 1 0 0 0 0\n0.5 0.5 1e0 255 255 255\n4 0 1 2 3\n3 0 1 "
    "4\n0 1\n";

void expect_invalid(std::string_view bytes, bool ply, const std::string& text) {
  try {
    if (ply)
      parse_ply(bytes, "in.ply");
    else
      parse_obj(bytes, "in.obj");
    ADD_FAILURE() << "no exception, expected " << text;
  } catch (const InvalidInput& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(ply ? "in.ply" : "in.obj", 0), 0u) << what;
    EXPECT_NE(what.find(text), std::string::npos) << what;
  }
}

TEST(PlyReader, AsciiPolygonsAreFanTriangulatedAndOtherElementsSkipped) {
  const MeshData m = parse_ply(kAsciiQuad, "quad.ply");
  ASSERT_EQ(m.vertex_count(), 5u);
  EXPECT_EQ(m.triangles, (std::vector<std::array<std::int64_t, 3>>{{0, 1, 2}, {0, 2, 3}, {0, 1, 4}}));
  ASSERT_NE(m.attribute("color"), nullptr);
  EXPECT_EQ(m.attribute("color")->values[0], 1.0f);
  EXPECT_EQ(m.attribute("color")->values[4], 1.0f);
  EXPECT_EQ(m.positions[4], (std::array<double, 3>{0.5, 0.5, 1.0}));
}

// Binary body of a two-triangle mesh with uint8 counts and uint32 indices, in either byte order.
std::string binary_mesh(bool big, const std::string& count_type = "uchar") {
  std::string s =
      std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
      " 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\nproperty short id\n"
      "element face 2\nproperty list " +
      count_type + " uint vertex_indices\nend_header\n";
  auto put = [&](const void* p, std::size_t n) {
    std::string b(static_cast<const char*>(p), n);
    if (big) std::reverse(b.begin(), b.end());
    s += b;
  };
  for (int v = 0; v < 4; ++v) {
    for (int c = 0; c < 3; ++c) {
      const double x = v * 10 + c + 0.125;
      put(&x, 8);
    }
    const std::int16_t id = static_cast<std::int16_t>(-v);
    put(&id, 2);
  }
  for (int f = 0; f < 2; ++f) {
    if (count_type == "uchar")
      s += '\3';
    else {
      const std::uint16_t n = 3;
      put(&n, 2);
    }
    for (std::uint32_t i : {0u, 1u + f, 2u + f}) put(&i, 4);
  }
  return s;
}

TEST(PlyReader, BinaryBothByteOrdersAndTypes) {
  for (bool big : {false, true})
    for (const char* ct : {"uchar", "ushort"}) {
      const MeshData m = parse_ply(binary_mesh(big, ct), "b.ply");
      ASSERT_EQ(m.vertex_count(), 4u);
      EXPECT_EQ(m.positions[3], (std::array<double, 3>{30.125, 31.125, 32.125}));
      EXPECT_EQ(*m.ids, (std::vector<std::int64_t>{0, -1, -2, -3}));
      EXPECT_EQ(m.triangles, (std::vector<std::array<std::int64_t, 3>>{{0, 1, 2}, {0, 2, 3}}));
    }
}

TEST(PlyReader, BinaryFaultsNameTheByte) {
  const std::string good = binary_mesh(false);
  expect_invalid(good.substr(0, good.size() - 1), true, "truncated data");
  expect_invalid(good + "x", true, "1 trailing bytes");
  std::string lying = good;
  lying.replace(lying.find("element face 2"), 14, "element face 9");
  expect_invalid(lying, true, "byte ");
  std::string bad_index = good;
  bad_index[bad_index.size() - 4] = 7;
  expect_invalid(bad_index, true, "vertex index 7 out of range");
}

TEST(PlyReader, HeaderFaults) {
  expect_invalid("", true, "empty file");
  expect_invalid("plx\n", true, "not a PLY file");
  expect_invalid("ply\nelement vertex 1\nproperty float x\nend_header\n", true, "no 'format' line");
  expect_invalid("ply\nformat ascii 1.0\nelement vertex -1\n", true, "bad element count");
  expect_invalid("ply\nformat ascii 1.0\nproperty float x\n", true, "property before any element");
  expect_invalid("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", true, "without end_header");
  expect_invalid(
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n", true,
      "no scalar property 'z'");
  expect_invalid(
      "ply\nformat ascii 1.0\nelement vertex 18446744073709551615\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n0 0 0\n",
      true, "declares");
}

TEST(PlyReader, AsciiFaults) {
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  expect_invalid(head + "0 0 0\n1 0 0\n0 1 nan\n3 0 1 2\n", true, "non-finite");
  expect_invalid(head + "0 0 0\n1 0 0\n0 1 abc\n3 0 1 2\n", true, "in.ply:12: bad float value 'abc'");
  expect_invalid(head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", true, "vertex index 3 out of range");
  expect_invalid(head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n", true, "vertex index -1 out of range");
  expect_invalid(head + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n", true, "has 2 vertices");
  expect_invalid(head + "0 0 0\n1 0 0\n0 1 0\n3 0 1\n", true, "truncated data");
  expect_invalid(head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n7\n", true, "trailing data");
  expect_invalid(head + "0 0 0\n1 0 0\n0 1 0\n300 0 1 2\n", true, "bad uchar value '300'");
}

TEST(PlyReader, AsciiLyingCountIsRejectedBeforeAllocation) {
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n";
  EXPECT_NO_THROW(parse_ply(head + "0 0 0\n1 0 0\n0 1 0\n0 0 1", "in.ply"));  // no final newline
  std::string lying = head + "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
  lying.replace(lying.find("vertex 4"), 8, "vertex 5");
  expect_invalid(lying, true, "element 'vertex' declares 5 records but only 24 bytes remain");
}

TEST(Readers, BinaryGarbageIsQuotedPrintably) {
  expect_invalid(std::string("v 0 0 \x01\xff\n", 9), false, "non-numeric token '\\x01\\xff' in vertex");
  expect_invalid("v 0 0 " + std::string(100, 'z') + "\n", false, "'" + std::string(40, 'z') + "...'");
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n";
  expect_invalid(head + "0 0 \x7f\n", true, "bad float value '\\x7f'");
}

TEST(ObjReader, CornersNegativeIndicesAndPolygons) {
  const std::string text =
      "# c\nmtllib x.mtl\nv 0 0 0\nv 1 0 0 1.0\nv 1 1 0 0.5 0.5 0.5\nvt 0 0\nvn 0 0 1\n"
      "v 0 1 0\ng group\ns off\nf 1/1/1 2/1/1 3//1 4\nf -4 -3 -1\n";
  const MeshData m = parse_obj(text, "in.obj");
  ASSERT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(m.triangles, (std::vector<std::array<std::int64_t, 3>>{{0, 1, 2}, {0, 2, 3}, {0, 1, 3}}));
}

TEST(ObjReader, Faults) {
  expect_invalid("", false, "empty file");
  expect_invalid("# only a comment\n", false, "no vertices");
  expect_invalid("v 0 0\n", false, "in.obj:1: vertex with 2 coordinates");
  expect_invalid("v 0 0 inf\n", false, "non-finite");
  expect_invalid("v 0 0 1x\n", false, "non-numeric token '1x'");
  expect_invalid("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", false, "index 0");
  expect_invalid("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", false, "vertex index 4 out of range");
  expect_invalid("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", false, "relative index -4");
  expect_invalid("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", false, "face with 2 vertices");
  expect_invalid("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", false, "non-numeric face corner 'x'");
  expect_invalid("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999\n", false, "in.obj:4");
}

TEST(MeshReader, UnknownExtensionAndMissingFile) {
  test::TempDir d;
  const auto stl = d.write("m.stl", "solid x\n");
  EXPECT_THROW(read_mesh(stl), InvalidInput);
  EXPECT_THROW(read_mesh(d / "missing.ply"), IoError);
  std::filesystem::create_directory(d / "folder.ply");
  EXPECT_THROW(read_mesh(d / "folder.ply"), IoError);
  EXPECT_THROW(read_mesh("/dev/null.ply"), IoError);
}

TEST(MappedFile, RejectsSpecialFilesWithoutBlocking) {
  EXPECT_THROW(MappedFile("/dev/null"), IoError);
  test::TempDir d;
  const auto fifo = d / "pipe.ply";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_THROW(read_mesh(fifo), IoError);  // would hang forever if open() waited for a writer
  const auto empty = d.write("empty.ply");
  const MappedFile f(empty);
  EXPECT_TRUE(f.empty());
}

}  // namespace
}  // namespace topotrack
