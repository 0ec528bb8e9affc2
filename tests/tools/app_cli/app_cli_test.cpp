// CLI tests of the §5 applications through the built `topotrack` binary: propagate, wave, export and render on a
// small tracked sequence (gen blobs, 4 frames, tracked by the fixture test cli.app.setup), checking the files
// written and their content, and bad input: exit code and a message naming the file or option at fault.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/mapped_file.hpp"
#include "io/mesh_reader.hpp"
#include "io/ply_writer.hpp"
#include "io/pc2.hpp"
#include "kernels/render/png.hpp"

namespace topotrack {
namespace {
namespace fs = std::filesystem;

const fs::path kScratch = APP_CLI_SCRATCH;
const fs::path kTracked = kScratch / "tracked";
const fs::path kInput = kScratch / "input";

struct CliRun {
  int code = -1;
  std::string out, err;
};

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

//! CliRun topotrack with `args`; stdout and stderr go through files in `dir` (the test's own folder).
CliRun run(const fs::path& dir, const std::vector<std::string>& args) {
  fs::create_directories(dir);
  std::string cmd = quote(TOPOTRACK_EXE);
  for (const auto& a : args) {
    cmd += ' ';
    cmd += quote(a);
  }
  cmd += " >";
  cmd += quote((dir / "stdout.txt").string());
  cmd += " 2>";
  cmd += quote((dir / "stderr.txt").string());
  const int status = std::system(cmd.c_str());
  CliRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = slurp(dir / "stdout.txt");
  r.err = slurp(dir / "stderr.txt");
  return r;
}

//! "<prefix>.<nnnn>.<ext>", as the commands name frames.
std::string numbered(const char* prefix, int n, const char* ext) {
  char name[128];
  std::snprintf(name, sizeof name, "%s.%04d.%s", prefix, n, ext);
  return name;
}

//! A fresh output folder for one test.
fs::path fresh(const std::string& name) {
  const fs::path d = kScratch / "out" / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::vector<fs::path> files(const fs::path& dir, const std::string& ext) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ext) out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

//! Exit code `exit_code` and a message on stderr containing `text` (the file or option at fault).
#define EXPECT_FAILS(r, exit_code, text)                                                                \
  do {                                                                                                  \
    EXPECT_EQ((r).code, exit_code) << (r).err;                                                          \
    EXPECT_NE((r).err.find("topotrack: error: "), std::string::npos) << (r).err;                        \
    EXPECT_NE((r).err.find(text), std::string::npos) << "stderr lacks '" << (text) << "': " << (r).err; \
  } while (0)

class AppCli : public ::testing::Test {
protected:
  static void SetUpTestSuite() {
    ASSERT_TRUE(fs::exists(kTracked / "track.json")) << "run the fixture test cli.app.setup first";
    tracked_ = files(kTracked, ".ply");
    ASSERT_EQ(tracked_.size(), 4u);
  }
  static std::vector<fs::path> tracked_;
};
std::vector<fs::path> AppCli::tracked_;

// propagate ------------------------------------------------------------------------------------------

TEST_F(AppCli, PropagateCheckerWritesColoursIntoEveryFrame) {
  const fs::path out = fresh("propagate_checker");
  const CliRun r = run(out / "log", {"propagate", kTracked.string(), "-o", (out / "frames").string(), "--source",
                                  "checker:cell=0.4", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("propagated 'color' (width 3) from frame 1 forward over 4 frames"), std::string::npos) << r.out;
  const auto written = files(out / "frames", ".ply");
  ASSERT_EQ(written.size(), 4u);
  EXPECT_EQ(files(out / "frames", ".events").size(), 3u);  // frames 2..4 keep their event lists
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(written[k].filename(), tracked_[k].filename());
    const MeshData in = read_mesh(tracked_[k]), d = read_mesh(written[k]);
    ASSERT_EQ(d.vertex_count(), in.vertex_count());
    ASSERT_TRUE(d.ids.has_value());
    EXPECT_EQ(*d.ids, *in.ids);
    EXPECT_EQ(d.positions, in.positions);
    const VertexAttribute* c = d.attribute("color");
    ASSERT_NE(c, nullptr) << written[k];
    ASSERT_EQ(c->width, 3);
    ASSERT_EQ(c->values.size(), 3 * d.vertex_count());
    // Two checker colours (stored as bytes): the default a = (0.95, 0.95, 0.92) and b = (0.12, 0.25, 0.65),
    // and blends of them where a topology patch or a split interpolates; both squares are present.
    std::size_t light = 0, dark = 0;
    for (std::size_t i = 0; i < d.vertex_count(); ++i) {
      const float b = c->values[3 * i + 2], red = c->values[3 * i];
      EXPECT_GE(b, 0.64f);
      if (red > 0.94f) ++light;
      if (red < 0.13f) ++dark;
    }
    EXPECT_GT(light, d.vertex_count() / 5) << written[k];
    EXPECT_GT(dark, d.vertex_count() / 5) << written[k];
  }
}

TEST_F(AppCli, PropagateScalarBackwardAndBothWays) {
  const fs::path out = fresh("propagate_scalar");
  CliRun r = run(out / "log1", {"propagate", kTracked.string(), "-o", (out / "back").string(), "--source",
                             "sine:cell=0.5,axis=y,a=0,b=1", "--name", "height", "--direction", "backward", "-q"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("from frame 4 backward over 4 frames"), std::string::npos) << r.out;
  for (const auto& f : files(out / "back", ".ply")) {
    const MeshData d = read_mesh(f);
    const VertexAttribute* h = d.attribute("height");
    ASSERT_NE(h, nullptr) << f;
    EXPECT_EQ(h->width, 1);
    EXPECT_EQ(h->values.size(), d.vertex_count());
    const auto [lo, hi] = std::minmax_element(h->values.begin(), h->values.end());
    EXPECT_GE(*lo, -1e-6f);
    EXPECT_LE(*hi, 1 + 1e-6f);
    EXPECT_GT(*hi - *lo, 0.5f) << f;
  }
  r = run(out / "log2", {"propagate", kTracked.string(), "-o", (out / "both").string(), "--source",
                         "constant:value=0.25/0.5", "--from", "2", "--direction", "both", "-q"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("from frame 2 both over 4 frames"), std::string::npos) << r.out;
  const auto both = files(out / "both", ".ply");
  ASSERT_EQ(both.size(), 4u);
  for (const auto& f : both) {
    const MeshData d = read_mesh(f);
    const VertexAttribute* v = d.attribute("value");
    ASSERT_NE(v, nullptr) << f;
    ASSERT_EQ(v->width, 2);
    ASSERT_EQ(v->values.size(), 2 * d.vertex_count());
    // A constant stays constant through every rule (weights sum to one), up to float rounding.
    for (std::size_t i = 0; i < d.vertex_count(); ++i) {
      EXPECT_NEAR(v->values[2 * i], 0.25f, 1e-5f);
      EXPECT_NEAR(v->values[2 * i + 1], 0.5f, 1e-5f);
    }
  }
}

TEST_F(AppCli, PropagateDisplacementMovesVertices) {
  const fs::path out = fresh("propagate_displace");
  const CliRun r = run(out / "log", {"propagate", kTracked.string(), "-o", (out / "frames").string(), "--source",
                                  "stripes:cell=0.3,a=0,b=1", "--displace", "0.05", "-q"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto written = files(out / "frames", ".ply");
  ASSERT_EQ(written.size(), 4u);
  const MeshData in = read_mesh(tracked_.back()), d = read_mesh(written.back());
  ASSERT_EQ(d.vertex_count(), in.vertex_count());
  const VertexAttribute* v = d.attribute("value");
  ASSERT_NE(v, nullptr);
  // Each vertex moves along its unit normal by 0.05 x its propagated value (1 or 0 on the stripes, blends
  // between them where splits interpolated).
  std::size_t moved = 0, still = 0;
  for (std::size_t i = 0; i < d.vertex_count(); ++i) {
    double dist2 = 0;
    for (int c = 0; c < 3; ++c) dist2 += (d.positions[i][c] - in.positions[i][c]) * (d.positions[i][c] - in.positions[i][c]);
    EXPECT_NEAR(std::sqrt(dist2), 0.05 * std::abs(v->values[i]), 1e-5) << "vertex " << i;
    if (v->values[i] == 1.0f) ++moved;
    if (v->values[i] == 0.0f) ++still;
  }
  EXPECT_GT(moved, 0u);
  EXPECT_GT(still, 0u);
}

TEST_F(AppCli, PropagateRoundTripReportsError) {
  const fs::path out = fresh("propagate_round_trip");
  CliRun r = run(out / "l1", {"propagate", kTracked.string(), "--source", "sine:axis=1/1/0,a=0,b=1", "--round-trip"});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::size_t n = read_mesh(tracked_[0]).vertex_count();
  std::string expected = "round trip frame 1 -> 4 -> 1: ";
  expected += std::to_string(n);
  expected += " values (width 1)";
  EXPECT_NE(r.out.find(expected), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("; 0 ids lost;"), std::string::npos) << r.out;
  // Four frames a quarter turn apart resample much of the surface; still most values come back close.
  const std::size_t mean_at = r.out.find("mean ");
  ASSERT_NE(mean_at, std::string::npos) << r.out;
  const double mean = std::stod(r.out.substr(mean_at + 5));
  EXPECT_GT(mean, 0.0) << r.out;
  EXPECT_LT(mean, 0.1) << r.out;
  // A constant survives any number of events exactly (up to float rounding).
  r = run(out / "l2", {"propagate", kTracked.string(), "--source", "constant:value=0.5", "--round-trip"});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::size_t at = r.out.find("|error| max ");
  ASSERT_NE(at, std::string::npos) << r.out;
  EXPECT_LT(std::stod(r.out.substr(at + 12)), 1e-6) << r.out;
  r = run(out / "l3", {"propagate", kTracked.string(), "--round-trip", "-o", (out / "x").string()});
  EXPECT_FAILS(r, 2, "--round-trip writes nothing");
  EXPECT_FALSE(fs::exists(out / "x"));
}

TEST_F(AppCli, PropagateRejectsBadInput) {
  const fs::path out = fresh("propagate_bad");
  const std::string o = (out / "frames").string();
  CliRun r = run(out / "l1", {"propagate", (kScratch / "no_such_folder").string(), "-o", o, "-q"});
  EXPECT_FAILS(r, 3, "no_such_folder");
  EXPECT_NE(r.err.find("no such file or folder"), std::string::npos) << r.err;
  r = run(out / "l2", {"propagate", kTracked.string(), "-o", o, "--source", "attribute:name=nope", "-q"});
  EXPECT_FAILS(r, 3, "blobs.0001.ply: no vertex attribute 'nope'");
  r = run(out / "l3", {"propagate", kTracked.string(), "-o", o, "--from", "99", "-q"});
  EXPECT_FAILS(r, 2, "--from 99: no frame with that number");
  r = run(out / "l4", {"propagate", kTracked.string(), "-o", o, "--source", "plaid", "-q"});
  EXPECT_FAILS(r, 3, "unknown pattern 'plaid'");
  r = run(out / "l5", {"propagate", kTracked.string(), "-o", o, "--source", "image:file=" + (out / "none.png").string(),
                       "-q"});
  EXPECT_FAILS(r, 1, "none.png");
  // Frames without ids (the untracked input) and a tracked sequence with an event list missing.
  r = run(out / "l6", {"propagate", kInput.string(), "-o", o, "-q"});
  EXPECT_FAILS(r, 3, "blobs.0001.ply: no vertex ids");
  const fs::path holey = out / "holey";
  fs::create_directories(holey);
  for (const auto& f : fs::directory_iterator(kTracked))
    if (f.path().filename() != "blobs.0003.events") fs::copy_file(f.path(), holey / f.path().filename());
  r = run(out / "l7", {"propagate", holey.string(), "-o", o, "-q"});
  EXPECT_FAILS(r, 3, "blobs.0003.events: missing event list");
  r = run(out / "l8", {"propagate", kTracked.string(), "-q"});
  EXPECT_FAILS(r, 2, "give exactly one of -o OUT and --in-place");
}

// wave -----------------------------------------------------------------------------------------------

TEST_F(AppCli, WaveWritesDisplacedFramesAndLog) {
  const fs::path out = fresh("wave");
  const CliRun r = run(out / "log", {"wave", kTracked.string(), "-o", (out / "frames").string(), "--inject", "1", "-q"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto written = files(out / "frames", ".ply");
  ASSERT_EQ(written.size(), 4u);
  double max_height = 0;
  for (std::size_t k = 0; k < 4; ++k) {
    const MeshData in = read_mesh(tracked_[k]), d = read_mesh(written[k]);
    ASSERT_EQ(d.vertex_count(), in.vertex_count());
    const VertexAttribute* h = d.attribute("height");
    ASSERT_NE(h, nullptr) << written[k];
    ASSERT_EQ(h->width, 1);
    ASSERT_EQ(h->values.size(), d.vertex_count());
    for (std::size_t i = 0; i < d.vertex_count(); ++i) {
      max_height = std::max(max_height, double(std::abs(h->values[i])));
      if (h->values[i] == 0.0f) {
        for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(float(d.positions[i][c]), float(in.positions[i][c]));
      }
    }
  }
  const nlohmann::json log = nlohmann::json::parse(slurp(out / "frames" / "wave.json"));
  ASSERT_EQ(log.at("frames").size(), 4u);
  std::size_t injected = 0;
  for (const auto& f : log.at("frames")) injected += f.at("injected").get<std::size_t>();
  EXPECT_EQ(log.at("frames")[0].at("injected").get<std::size_t>(), 0u);  // nothing before the first events
  // Energy enters only where topology patches created vertices (§5); a height appears exactly when some did.
  EXPECT_EQ(injected > 0, max_height > 0) << "injected " << injected << ", max |h| " << max_height;
}

TEST_F(AppCli, WaveRejectsBadInput) {
  const fs::path out = fresh("wave_bad");
  const std::string o = (out / "frames").string();
  CliRun r = run(out / "l1", {"wave", (kScratch / "no_such_folder").string(), "-o", o, "-q"});
  EXPECT_FAILS(r, 3, "no_such_folder");
  r = run(out / "l2", {"wave", kInput.string(), "-o", o, "-q"});
  EXPECT_FAILS(r, 3, "blobs.0001.ply: no vertex ids");
  r = run(out / "l3", {"wave", kTracked.string(), "-o", o, "--fps", "0", "-q"});
  EXPECT_FAILS(r, 2, "--fps must be positive");
  r = run(out / "l4", {"wave", kTracked.string(), "-o", o, "--substeps", "-3", "-q"});
  EXPECT_FAILS(r, 2, "--substeps");
}

// export ---------------------------------------------------------------------------------------------

TEST_F(AppCli, ExportWritesBaseMeshAndPointCachePerStretch) {
  const fs::path out = fresh("export");
  // A sequence with a stretch of constant connectivity: tracked frame 1 moved three times, then frame 2.
  const fs::path seq = out / "seq";
  fs::create_directories(seq);
  MeshData base = read_mesh(tracked_[0]);
  const std::vector<std::array<double, 3>> rest = base.positions;
  for (int k = 1; k <= 3; ++k) {
    for (std::size_t i = 0; i < rest.size(); ++i) base.positions[i] = {rest[i][0] + 0.125 * k, rest[i][1], rest[i][2]};
    write_ply(seq / numbered("s", k, "ply"), base);
  }
  fs::copy_file(tracked_[1], seq / "s.0004.ply");
  const CliRun r = run(out / "log", {"export", seq.string(), "-o", (out / "cache").string(), "-q"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("4 frames in 2 stretches"), std::string::npos) << r.out;
  const nlohmann::json manifest = nlohmann::json::parse(slurp(out / "cache" / "export.json"));
  ASSERT_EQ(manifest.at("stretches").size(), 2u);
  const auto& s0 = manifest.at("stretches")[0];
  EXPECT_EQ(s0.at("first_frame").get<long>(), 1);
  EXPECT_EQ(s0.at("last_frame").get<long>(), 3);
  const MeshData mesh0 = read_mesh(out / "cache" / s0.at("mesh").get<std::string>());
  EXPECT_EQ(mesh0.vertex_count(), rest.size());
  const Pc2Data c0 = read_pc2(out / "cache" / s0.at("cache").get<std::string>());
  EXPECT_EQ(c0.header.points, std::int32_t(rest.size()));
  EXPECT_EQ(c0.header.samples, 3);
  EXPECT_EQ(c0.header.start_frame, 1.0f);
  for (int k = 0; k < 3; ++k)
    for (std::size_t i = 0; i < rest.size(); i += 97) {
      EXPECT_FLOAT_EQ(c0.sample(k)[3 * i], float(rest[i][0] + 0.125 * (k + 1)));
      EXPECT_FLOAT_EQ(c0.sample(k)[3 * i + 2], float(rest[i][2]));
    }
  const auto& s1 = manifest.at("stretches")[1];
  const Pc2Data c1 = read_pc2(out / "cache" / s1.at("cache").get<std::string>());
  EXPECT_EQ(c1.header.samples, 1);
  EXPECT_EQ(c1.header.start_frame, 4.0f);
  EXPECT_EQ(std::size_t(c1.header.points), read_mesh(tracked_[1]).vertex_count());
  // The tracked sequence itself: every frame lands in exactly one stretch.
  const CliRun t = run(out / "log2", {"export", kTracked.string(), "-o", (out / "tracked").string(), "--format", "ply", "-q"});
  ASSERT_EQ(t.code, 0) << t.err;
  const nlohmann::json m2 = nlohmann::json::parse(slurp(out / "tracked" / "export.json"));
  std::size_t samples = 0;
  for (const auto& s : m2.at("stretches")) {
    const Pc2Data c = read_pc2(out / "tracked" / s.at("cache").get<std::string>());
    EXPECT_EQ(std::size_t(c.header.samples), s.at("frames").get<std::size_t>());
    samples += std::size_t(c.header.samples);
  }
  EXPECT_EQ(samples, 4u);
}

TEST_F(AppCli, ExportRejectsBadInput) {
  const fs::path out = fresh("export_bad");
  const std::string o = (out / "cache").string();
  CliRun r = run(out / "l1", {"export", (kScratch / "no_such_folder").string(), "-o", o, "-q"});
  EXPECT_FAILS(r, 3, "no_such_folder");
  r = run(out / "l2", {"export", kTracked.string(), "-o", o, "--format", "stl", "-q"});
  EXPECT_FAILS(r, 2, "--format must be obj or ply");
  const fs::path seq = out / "seq";
  fs::create_directories(seq);
  fs::copy_file(tracked_[0], seq / "s.0001.ply");
  std::ofstream(seq / "s.0002.ply") << "ply\nformat ascii 1.0\nelement vertex 3\nend_header\n";
  r = run(out / "l3", {"export", seq.string(), "-o", o, "-q"});
  EXPECT_FAILS(r, 3, "s.0002.ply");
}

// render ---------------------------------------------------------------------------------------------

//! A decoded PNG with more than one colour in it.
void expect_picture(const fs::path& p, int w, int h) {
  ASSERT_TRUE(fs::exists(p)) << p;
  const Image im = read_png(p);
  EXPECT_EQ(im.width, w) << p;
  EXPECT_EQ(im.height, h) << p;
  std::set<std::uint32_t> colours;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      const std::uint8_t* px = im.pixel(x, y);
      colours.insert(std::uint32_t(px[0]) << 16 | std::uint32_t(px[1]) << 8 | px[2]);
    }
  EXPECT_GT(colours.size(), 10u) << p;
}

TEST_F(AppCli, RenderFramesSheetTurntableAndDiff) {
  const fs::path out = fresh("render");
  CliRun r = run(out / "l0", {"propagate", kTracked.string(), "-o", (out / "textured").string(), "-q"});
  ASSERT_EQ(r.code, 0) << r.err;
  r = run(out / "l1", {"render", (out / "textured").string(), "-o", (out / "pictures").string(), "--width", "64",
                       "--height", "48", "--samples", "1", "--sheet", "4", "--sheet-size", "32", "-q"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto pngs = files(out / "pictures", ".png");
  ASSERT_EQ(pngs.size(), 5u);  // 4 frames and the sheet
  for (int k = 1; k <= 4; ++k) expect_picture(out / "pictures" / numbered("blobs", k, "png"), 64, 48);
  expect_picture(out / "pictures" / "contact_sheet.png", 2 * 32 + 3 * 4, 2 * 32 + 3 * 4);
  // The checker shows: strongly blue pixels (b) next to light ones (a).
  const Image first = read_png(out / "pictures" / "blobs.0001.png");
  std::size_t blue = 0;
  for (int y = 0; y < first.height; ++y)
    for (int x = 0; x < first.width; ++x)
      if (first.pixel(x, y)[2] > first.pixel(x, y)[0] + 40) ++blue;
  EXPECT_GT(blue, 20u);

  r = run(out / "l2", {"render", (out / "textured" / "blobs.0002.ply").string(), "-o", (out / "turn").string(),
                       "--width", "40", "--height", "40", "--samples", "1", "--turntable", "3", "--no-frames", "-q"});
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_EQ(files(out / "turn", ".png").size(), 3u);
  for (int i = 0; i < 3; ++i) expect_picture(out / "turn" / numbered("turntable", i, "png"), 40, 40);

  r = run(out / "l3", {"render", "--diff", (out / "turn" / "turntable.0000.png").string(),
                       (out / "turn" / "turntable.0000.png").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("mean |diff| 0.000"), std::string::npos) << r.out;
  r = run(out / "l4", {"render", "--diff", (out / "turn" / "turntable.0000.png").string(),
                       (out / "turn" / "turntable.0001.png").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out.find("mean |diff| 0.000"), std::string::npos) << r.out;
}

TEST_F(AppCli, RenderRejectsBadInput) {
  const fs::path out = fresh("render_bad");
  const std::string o = (out / "pictures").string();
  CliRun r = run(out / "l1", {"render", (kScratch / "no_such_folder").string(), "-o", o, "-q"});
  EXPECT_FAILS(r, 3, "no_such_folder");
  r = run(out / "l2", {"render", kTracked.string(), "-o", o, "--color", "nope", "--width", "16", "--height", "16", "-q"});
  EXPECT_FAILS(r, 3, "blobs.0001.ply: no vertex attribute 'nope'");
  r = run(out / "l3", {"render", kTracked.string(), "-o", o, "--turntable", "2", "--turntable-frame", "99", "-q"});
  EXPECT_FAILS(r, 2, "--turntable-frame 99: no such frame");
  r = run(out / "l4", {"render", kTracked.string(), "-o", o, "--every", "0", "-q"});
  EXPECT_FAILS(r, 2, "--every must be at least 1");
  r = run(out / "l5", {"render", kTracked.string(), "-o", o, "--samples", "9", "-q"});
  EXPECT_FAILS(r, 2, "--samples");
  r = run(out / "l6", {"render", "--diff", (out / "a.png").string(), (out / "b.png").string()});
  EXPECT_FAILS(r, 1, "a.png");
  r = run(out / "l7", {"render", kTracked.string(), "-o", o, "--follow", (out / "motion.json").string(), "-q"});
  EXPECT_FAILS(r, 1, "motion.json");
}

}  // namespace
}  // namespace topotrack
