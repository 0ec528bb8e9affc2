// Atomic writes: the target holds either the old bytes or the complete new ones; no temporary is left behind.
#include "io/atomic_file.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

#include "io/error.hpp"
#include "io/event_file.hpp"
#include "io/ply_writer.hpp"
#include "tests/io/sample_meshes.hpp"
#include "tests/io/temp_dir.hpp"

namespace topotrack {
namespace {

using test::read_all;
using test::TempDir;

TEST(AtomicFile, CreatesAndReplaces) {
  TempDir d;
  write_file_atomic(d / "f.txt", "first");
  EXPECT_EQ(read_all(d / "f.txt"), "first");
  write_file_atomic(d / "f.txt", std::string(3 << 20, 'x'));  // larger than the buffer
  EXPECT_EQ(read_all(d / "f.txt"), std::string(3 << 20, 'x'));
  EXPECT_EQ(d.entries(), (std::vector<std::string>{"f.txt"}));
}

TEST(AtomicFile, StreamingWritesInPieces) {
  TempDir d;
  write_file_atomic(d / "s.bin", [](AtomicFileWriter& w) {
    for (int i = 0; i < 1000; ++i) w.write(std::string(4099, static_cast<char>('a' + i % 26)));
  });
  const std::string s = read_all(d / "s.bin");
  ASSERT_EQ(s.size(), 4099u * 1000u);
  EXPECT_EQ(s[4099 * 27], 'b');
}

TEST(AtomicFile, ProducerFailureLeavesTheOldFile) {
  TempDir d;
  write_file_atomic(d / "f.txt", "old");
  EXPECT_THROW(write_file_atomic(d / "f.txt",
                                 [](AtomicFileWriter& w) {
                                   w.write(std::string(5 << 20, 'n'));  // part of it already on disk
                                   throw std::runtime_error("producer failed");
                                 }),
               std::runtime_error);
  EXPECT_EQ(read_all(d / "f.txt"), "old");
  EXPECT_EQ(d.entries(), (std::vector<std::string>{"f.txt"}));
}

TEST(AtomicFile, WriterFailureLeavesTheOldFile) {
  TempDir d;
  write_file_atomic(d / "m.ply", "old mesh");
  MeshData bad = test::octahedron();
  bad.triangles[5][2] = 17;
  EXPECT_THROW(write_ply(d / "m.ply", bad), InvalidInput);
  EXPECT_EQ(read_all(d / "m.ply"), "old mesh");
  EventList nan_events;
  nan_events.record_split(1, 2, 3, std::numeric_limits<double>::quiet_NaN());
  write_file_atomic(d / "e.events", "old events");
  EXPECT_THROW(write_events(d / "e.events", nan_events), InvalidInput);
  EXPECT_EQ(read_all(d / "e.events"), "old events");
  EXPECT_EQ(d.entries(), (std::vector<std::string>{"e.events", "m.ply"}));
}

TEST(AtomicFile, DestroyedWithoutCommitRemovesTheTemporary) {
  TempDir d;
  write_file_atomic(d / "f.txt", "old");
  {
    AtomicFileWriter w(d / "f.txt");
    w.write("half");
    EXPECT_TRUE(std::filesystem::exists(w.temp_path()));
  }
  EXPECT_EQ(read_all(d / "f.txt"), "old");
  EXPECT_EQ(d.entries(), (std::vector<std::string>{"f.txt"}));
}

TEST(AtomicFile, UnwritableTargetsThrowIoErrorNamingThePath) {
  TempDir d;
  const auto p = d / "missing" / "f.txt";
  try {
    write_file_atomic(p, "x");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
  }
  std::filesystem::create_directory(d / "dir");
  EXPECT_THROW(write_file_atomic(d / "dir", "x"), IoError);  // rename over a folder fails
  EXPECT_TRUE(std::filesystem::is_directory(d / "dir"));
  EXPECT_EQ(d.entries(), (std::vector<std::string>{"dir"}));
  EXPECT_THROW(write_file_atomic(d.path() / "", "x"), IoError);
}

}  // namespace
}  // namespace topotrack
