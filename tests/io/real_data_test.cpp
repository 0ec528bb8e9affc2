// Every frame of the real sequences in ../shared/data reads, with the sizes its README states.
#include <gtest/gtest.h>

#include <filesystem>

#include "io/mesh_reader.hpp"
#include "io/ply_reader.hpp"
#include "io/ply_writer.hpp"
#include "io/sequence.hpp"

namespace topotrack {
namespace {

struct Expected {
  const char* name;
  std::size_t frames;
  std::size_t vertices;
};

class RealData : public ::testing::TestWithParam<Expected> {};

TEST_P(RealData, EveryFrameReads) {
  const std::filesystem::path dir = std::filesystem::path(TOPOTRACK_SHARED_DIR) / "data" / GetParam().name;
  if (!std::filesystem::is_directory(dir)) GTEST_SKIP() << dir << " is absent";
  const FrameSequence seq = find_frames(dir.string());
  EXPECT_TRUE(seq.warnings.empty()) << ::testing::PrintToString(seq.warnings);
  ASSERT_EQ(seq.frames.size(), GetParam().frames);
  const auto pattern = find_frames((dir / (std::string(GetParam().name) + ".####.ply")).string());
  ASSERT_EQ(pattern.frames.size(), seq.frames.size());
  std::vector<std::array<std::int64_t, 3>> first_triangles;
  for (std::size_t k = 0; k < seq.frames.size(); ++k) {
    EXPECT_EQ(seq.frames[k].number, static_cast<long>(k + 1));
    EXPECT_EQ(pattern.frames[k].path, seq.frames[k].path);
    const MeshData m = read_mesh(seq.frames[k].path);
    ASSERT_EQ(m.vertex_count(), GetParam().vertices) << seq.frames[k].path;
    ASSERT_GT(m.triangle_count(), 0u);
    if (k == 0) {
      first_triangles = m.triangles;
      // Euler characteristic 2 of a closed genus-0 surface: F = 2V - 4.
      EXPECT_EQ(m.triangle_count(), 2 * m.vertex_count() - 4);
      // And the writer round-trips it bit for bit (the files hold floats).
      const MeshData back = parse_ply(encode_ply(m), "rt.ply");
      EXPECT_EQ(back.positions, m.positions);
      EXPECT_EQ(back.triangles, m.triangles);
    } else {
      EXPECT_EQ(m.triangles, first_triangles) << "connectivity must not change within " << GetParam().name;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Shared, RealData,
                         ::testing::Values(Expected{"samba", 60, 9971}, Expected{"pcow", 204, 2904},
                                           Expected{"elephant", 24, 42321}),
                         [](const auto& p) { return std::string(p.param.name); });

}  // namespace
}  // namespace topotrack
