// Frame-sequence discovery on temporary folders: every pattern kind, sorting, gaps, duplicates, mixed
// formats.
#include "io/sequence.hpp"

#include <gtest/gtest.h>

#include "io/error.hpp"
#include "tests/io/temp_dir.hpp"

namespace topotrack {
namespace {

using test::TempDir;

std::vector<long> numbers(const FrameSequence& s) {
  std::vector<long> n;
  for (const auto& f : s.frames) n.push_back(f.number);
  return n;
}
std::vector<std::string> names(const FrameSequence& s) {
  std::vector<std::string> n;
  for (const auto& f : s.frames) n.push_back(f.path.filename().string());
  return n;
}
bool any_warning_has(const FrameSequence& s, const std::string& text) {
  for (const auto& w : s.warnings)
    if (w.find(text) != std::string::npos) return true;
  return false;
}
void expect_invalid(const std::string& spec, const std::string& text) {
  try {
    find_frames(spec);
    ADD_FAILURE() << spec << ": no exception";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(spec), std::string::npos) << e.what();
  }
}

TEST(FindFrames, FolderSortsByFrameNumber) {
  TempDir d;
  for (const char* n : {"a.0010.ply", "a.0002.ply", "a.0001.ply", "a.0003.ply", "notes.txt",
                        ".a.0004.ply.tmp-1-0", ".hidden.0005.ply"})
    d.write(n);
  std::filesystem::create_directory(d / "sub.0006.ply");
  const FrameSequence s = find_frames(d.path().string());
  EXPECT_EQ(numbers(s), (std::vector<long>{1, 2, 3, 10}));
  EXPECT_EQ(s.frames[0].path, d / "a.0001.ply");
  EXPECT_TRUE(any_warning_has(s, "6 frame(s) missing between 3 and 10"))
      << ::testing::PrintToString(s.warnings);
}

TEST(FindFrames, NaturalSortOfUnpaddedNumbers) {
  TempDir d;
  for (const char* n : {"frame_10.obj", "frame_2.obj", "frame_1.obj", "frame_9.obj", "frame_11.obj"})
    d.write(n);
  const FrameSequence s = find_frames(d.path().string());
  EXPECT_EQ(numbers(s), (std::vector<long>{1, 2, 9, 10, 11}));
}

TEST(FindFrames, ExtensionsAreCaseInsensitiveAndVdbCounts) {
  TempDir d;
  d.write("x_1.PLY");
  d.write("x_2.Obj");
  d.write("x_3.vdb");
  d.write("x_4.stl");
  const FrameSequence s = find_frames(d.path().string());
  EXPECT_EQ(numbers(s), (std::vector<long>{1, 2, 3}));
  EXPECT_TRUE(any_warning_has(s, "mixed file formats"));
}

TEST(FindFrames, HashPatternIsPadded) {
  TempDir d;
  for (const char* n :
       {"a.0001.ply", "a.0002.ply", "a.01.ply", "a.12345.ply", "a.0003.obj", "b.0004.ply", "a.01234.ply"})
    d.write(n);
  const FrameSequence s = find_frames((d / "a.####.ply").string());
  EXPECT_EQ(names(s), (std::vector<std::string>{"a.0001.ply", "a.0002.ply", "a.12345.ply"}));
  EXPECT_EQ(numbers(s), (std::vector<long>{1, 2, 12345}));
}

TEST(FindFrames, PrintfPattern) {
  TempDir d;
  for (const char* n : {"m.0007.obj", "m.0008.obj", "m.008.obj", "m.0009.ply"}) d.write(n);
  EXPECT_EQ(numbers(find_frames((d / "m.%04d.obj").string())), (std::vector<long>{7, 8}));
  TempDir e;
  for (const char* n : {"m.7.obj", "m.10.obj", "m.8.obj"}) e.write(n);
  const FrameSequence s = find_frames((e / "m.%d.obj").string());
  EXPECT_EQ(numbers(s), (std::vector<long>{7, 8, 10}));
  EXPECT_TRUE(any_warning_has(s, "1 frame(s) missing between 8 and 10"));
}

TEST(FindFrames, HoudiniPattern) {
  TempDir d;
  for (const char* n : {"fluid.0001.ply", "fluid.0002.ply", "fluid.1.ply", "fluid.0003.ply"}) d.write(n);
  EXPECT_EQ(numbers(find_frames((d / "fluid.$F4.ply").string())), (std::vector<long>{1, 2, 3}));
  TempDir e;
  for (const char* n : {"fluid.1.ply", "fluid.2.ply", "fluid.3.ply"}) e.write(n);
  EXPECT_EQ(numbers(find_frames((e / "fluid.$F.ply").string())), (std::vector<long>{1, 2, 3}));
}

TEST(FindFrames, BracePatternTakesAnyDigits) {
  TempDir d;
  for (const char* n : {"s.1.ply", "s.0002.ply", "s.30.ply", "s.x.ply", "s..ply"}) d.write(n);
  const FrameSequence s = find_frames((d / "s.{}.ply").string());
  EXPECT_EQ(numbers(s), (std::vector<long>{1, 2, 30}));
}

TEST(FindFrames, FrameFieldInsideTheName) {
  TempDir d;
  for (const char* n : {"run3_0001_surface.ply", "run3_0002_surface.ply", "run3_0002_points.ply"}) d.write(n);
  EXPECT_EQ(numbers(find_frames((d / "run3_####_surface.ply").string())), (std::vector<long>{1, 2}));
}

TEST(FindFrames, Glob) {
  TempDir d;
  for (const char* n : {"out_3.ply", "out_1.ply", "out_2.ply", "out_2.obj", "in_4.ply", "out_12.ply"})
    d.write(n);
  EXPECT_EQ(numbers(find_frames((d / "out_*.ply").string())), (std::vector<long>{1, 2, 3, 12}));
  EXPECT_EQ(numbers(find_frames((d / "out_?.ply").string())), (std::vector<long>{1, 2, 3}));
  EXPECT_EQ(names(find_frames((d / "*_1.*").string())), (std::vector<std::string>{"out_1.ply"}));
  expect_invalid((d / "*_2.*").string(), "frame number 2 appears twice: out_2.obj and out_2.ply");
}

TEST(FindFrames, StrideIsNotAGap) {
  TempDir d;
  for (const char* n : {"f.0000.ply", "f.0010.ply", "f.0020.ply", "f.0030.ply"}) d.write(n);
  const FrameSequence s = find_frames(d.path().string());
  EXPECT_EQ(numbers(s), (std::vector<long>{0, 10, 20, 30}));
  EXPECT_TRUE(s.warnings.empty()) << ::testing::PrintToString(s.warnings);
  d.write("f.0050.ply");
  const FrameSequence t = find_frames(d.path().string());
  EXPECT_TRUE(any_warning_has(t, "1 frame(s) missing between 30 and 50"))
      << ::testing::PrintToString(t.warnings);
}

TEST(FindFrames, ManyGapsAreSummarised) {
  TempDir d;
  for (int i = 0; i < 40; i += 3) d.write("g." + std::to_string(i) + ".ply");
  d.write("g.1.ply");
  const FrameSequence s = find_frames(d.path().string());
  EXPECT_LE(s.warnings.size(), 11u);
  EXPECT_TRUE(any_warning_has(s, "further gap(s) not listed"));
}

TEST(FindFrames, MixedFormatsWarn) {
  TempDir d;
  d.write("a.0001.ply");
  d.write("a.0002.obj");
  d.write("a.0003.ply");
  const FrameSequence s = find_frames((d / "a.####.*").string());
  EXPECT_EQ(numbers(s), (std::vector<long>{1, 2, 3}));
  EXPECT_TRUE(any_warning_has(s, "mixed file formats: 1 x .obj 2 x .ply"))
      << ::testing::PrintToString(s.warnings);
}

TEST(FindFrames, DuplicateFrameNumbersAreRejected) {
  TempDir d;
  d.write("a.0001.ply");
  d.write("a.0001.obj");
  expect_invalid(d.path().string(), "frame number 1 appears twice");
  TempDir e;
  e.write("s.1.ply");
  e.write("s.001.ply");
  expect_invalid((e / "s.{}.ply").string(), "appears twice");
}

TEST(FindFrames, NothingFoundIsRejected) {
  TempDir d;
  expect_invalid(d.path().string(), "no .obj, .ply or .vdb files");
  d.write("readme.txt");
  expect_invalid(d.path().string(), "no .obj, .ply or .vdb files");
  expect_invalid((d / "a.####.ply").string(), "no file matches");
  expect_invalid((d / "nothing" / "a.####.ply").string(), "does not exist");
  expect_invalid((d / "missing.ply").string(), "no such file or folder");
  EXPECT_THROW(find_frames(""), InvalidInput);
  EXPECT_THROW(find_frames((d / "a.##.%d.ply").string()), InvalidInput);
}

TEST(FindFrames, PlainFileIsOneFrame) {
  TempDir d;
  const auto p = d.write("bunny_0042.ply");
  const FrameSequence s = find_frames(p.string());
  ASSERT_EQ(s.frames.size(), 1u);
  EXPECT_EQ(s.frames[0].number, 42);
  EXPECT_EQ(s.frames[0].path, p);
}

TEST(FindFrames, UnnumberedFilesComeFirstInNameOrder) {
  TempDir d;
  for (const char* n : {"b.ply", "a.ply", "c_2.ply", "c_1.ply"}) d.write(n);
  const FrameSequence s = find_frames(d.path().string());
  EXPECT_EQ(names(s), (std::vector<std::string>{"a.ply", "b.ply", "c_1.ply", "c_2.ply"}));
  EXPECT_TRUE(any_warning_has(s, "without a frame number"));
}

TEST(FindFrames, HugeDigitRunIsNotANumber) {
  TempDir d;
  d.write("x_123456789012345678901234567890.ply");
  d.write("x_5.ply");
  const FrameSequence s = find_frames(d.path().string());
  EXPECT_EQ(numbers(s), (std::vector<long>{-1, 5}));
}

}  // namespace
}  // namespace topotrack
