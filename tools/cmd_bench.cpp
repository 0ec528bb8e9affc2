// topotrack bench -o DIR: the Table 1 harness (issue 8). Generates standard sequences over a range of sizes
// (blobs at several resolutions, plus resurfaced ../shared/data captures when present), tracks each with a
// fixed thread count, and writes per-stage median seconds and shares in the form of the paper's Table 1:
// DIR/table1.json (what a dashboard reads), DIR/table1_flat.json ([{name, unit, value}]), DIR/table1.md and
// DIR/seconds_per_frame.png (seconds per frame against vertex count).
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "engine/frame_loader.hpp"
#include "engine/tracker.hpp"
#include "kernels/raycast/embree_scene.hpp"
#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "io/sequence.hpp"
#include "kernels/eval/plot.hpp"
#include "kernels/gen/gen_sequence.hpp"
#include "kernels/render/png.hpp"
#include "tools/cli_common.hpp"
#include "tools/commands.hpp"

namespace topotrack::cli {
namespace {
namespace fs = std::filesystem;
using json = nlohmann::json;

struct BenchOptions {
  std::string out;
  // ~10.6k, 38k, 75k, 151k, 300k and 395k vertices: the 10k–400k span (about 1.3 res² vertices).
  std::vector<int> resolutions{90, 170, 240, 340, 480, 550};
  std::vector<std::string> captures{"samba", "elephant"};
  std::string shared = "../shared/data";
  int frames = 4;
  int threads = 2;
  std::string profile = "default";
};

//! Track the frames of `dir` and summarise: medians over the frames after the first (the first frame is only
//! an improvement, not a tracking step).
json run_sequence(const std::string& name, const fs::path& dir, const TrackerParams& params) {
  Tracker tracker(params);
  std::vector<double> verts, coarse, fine, improve, sdf, topo, io, total;
  for (const auto& f : find_frames(dir.string()).frames) {
    const auto t0 = std::chrono::steady_clock::now();
    LoadedFrame frame = load_frame(f.path);
    const double load_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const FrameReport& r = frame.grid ? tracker.add_frame(*frame.grid, f.path.string()) : tracker.add_frame(frame.mesh, f.path.string());
    if (r.index == 0) continue;
    verts.push_back(double(r.vertices));
    coarse.push_back(r.seconds.coarse);
    fine.push_back(r.seconds.fine);
    improve.push_back(r.seconds.improve);
    sdf.push_back(r.seconds.signed_distance);
    topo.push_back(r.seconds.topology);
    io.push_back(load_seconds);
    total.push_back(r.seconds.total + load_seconds);
  }
  const double t = median(total);
  auto share = [&](const std::vector<double>& v) { return t > 0 ? median(v) / t : 0.0; };
  std::fprintf(stderr, "bench: %s: %.0f vertices, %.2f s per frame\n", name.c_str(), median(verts), t);
  return {{"name", name},
          {"frames", total.size()},
          {"vertices", {{"min", verts.empty() ? 0 : *std::min_element(verts.begin(), verts.end())},
                        {"median", median(verts)},
                        {"max", verts.empty() ? 0 : *std::max_element(verts.begin(), verts.end())}}},
          {"seconds_per_frame", t},
          {"seconds", {{"coarse", median(coarse)}, {"fine", median(fine)}, {"improve", median(improve)},
                       {"signed_distance", median(sdf)}, {"topology", median(topo)}, {"io", median(io)}}},
          {"share", {{"coarse", share(coarse)}, {"fine", share(fine)}, {"improve", share(improve)},
                     {"topology", t > 0 ? (median(sdf) + median(topo)) / t : 0.0}, {"io", share(io)}}}};
}

void run_bench(const BenchOptions& opt) {
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(opt.threads));
  const fs::path out(opt.out);
  ensure_directory(out);
  const TrackerParams params = load_profile(opt.profile);
  json rows = json::array();
  for (int res : opt.resolutions) {
    GenParams g;
    g.kind = "blobs";
    g.frames = 100;  // one full turn in 100 frames, the tracker's standard step; the first `frames` are tracked
    g.resolution = res;
    g.last_frame = opt.frames;
    const fs::path dir = out / ("blobs_r" + std::to_string(res));
    fs::remove_all(dir);
    generate_sequence(g, dir);
    rows.push_back(run_sequence("blobs r" + std::to_string(res), dir, params));
  }
  for (const auto& c : opt.captures) {
    const fs::path src = fs::path(opt.shared) / c;
    if (!fs::is_directory(src)) {
      std::fprintf(stderr, "bench: %s: no such folder, capture '%s' skipped\n", src.string().c_str(), c.c_str());
      continue;
    }
    GenParams g;
    g.kind = "resurface";
    g.source = src.string();
    g.frames = opt.frames;
    const fs::path dir = out / ("resurface_" + c);
    fs::remove_all(dir);
    generate_sequence(g, dir);
    rows.push_back(run_sequence("resurfaced " + c, dir, params));
  }

  const json paper = {{"ViscElast", {{"vertices", "60k-300k"}, {"frame_time", "45-153s"}, {"coarse", "87-93%"}, {"fine", "3-8%"}}},
                      {"Splash", {{"vertices", "280k-380k"}, {"frame_time", "105-220s"}, {"coarse", "81-89%"}, {"fine", "11-18%"}}},
                      {"Morph", {{"vertices", "77k-96k"}, {"frame_time", "17-21s"}, {"coarse", "67-73%"}, {"fine", "19-23%"}}},
                      {"PerfCap", {{"vertices", "214k-369k"}, {"frame_time", "150-174s"}, {"coarse", "70-73%"}, {"fine", "24-27%"}}}};
  const json result = {{"threads", opt.threads}, {"embree_isa", embree_isa()}, {"profile", opt.profile}, {"frames_tracked", opt.frames},
                       {"rows", rows}, {"paper_table1", paper}};
  write_file_atomic(out / "table1.json", result.dump(1) + "\n");

  json flat = json::array();
  for (const auto& r : rows) {
    const std::string n = r["name"];
    flat.push_back({{"name", n + " seconds per frame"}, {"unit", "s"}, {"value", r["seconds_per_frame"]}});
    flat.push_back({{"name", n + " vertices"}, {"unit", "count"}, {"value", r["vertices"]["median"]}});
    for (const char* s : {"coarse", "fine", "improve", "signed_distance", "topology", "io"})
      flat.push_back({{"name", n + " " + s}, {"unit", "s"}, {"value", r["seconds"][s]}});
  }
  write_file_atomic(out / "table1_flat.json", flat.dump(1) + "\n");

  std::string md = "| | vertices | frame time | coarse reg. | fine reg. | improve | topology (incl. SDF) | I/O |\n"
                   "| --- | --- | --- | --- | --- | --- | --- | --- |\n";
  char line[512];
  for (const auto& r : rows) {
    std::snprintf(line, sizeof line, "| %s | %.0f | %.2fs | %.0f%% | %.0f%% | %.0f%% | %.0f%% | %.0f%% |\n",
                  r["name"].get<std::string>().c_str(), r["vertices"]["median"].get<double>(),
                  r["seconds_per_frame"].get<double>(), 100 * r["share"]["coarse"].get<double>(),
                  100 * r["share"]["fine"].get<double>(), 100 * r["share"]["improve"].get<double>(),
                  100 * r["share"]["topology"].get<double>(), 100 * r["share"]["io"].get<double>());
    md += line;
  }
  for (const auto& [k, v] : paper.items()) {
    std::snprintf(line, sizeof line, "| paper: %s | %s | %s | %s | %s | negligible | negligible | |\n", k.c_str(),
                  v["vertices"].get<std::string>().c_str(), v["frame_time"].get<std::string>().c_str(),
                  v["coarse"].get<std::string>().c_str(), v["fine"].get<std::string>().c_str());
    md += line;
  }
  md += "\nMedians over the tracked frames after the first (frame time includes reading the frame), " + std::to_string(opt.threads) + " threads, profile `" +
        opt.profile + "`. The paper's figures: one i7-2600K, \"mostly sequential\".\n";
  write_file_atomic(out / "table1.md", md);

  PlotSeries s{"seconds per frame", {}, {}};
  for (const auto& r : rows) {
    s.x.push_back(r["vertices"]["median"].get<double>());
    s.y.push_back(r["seconds_per_frame"].get<double>());
  }
  std::vector<std::size_t> order(s.x.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return s.x[a] < s.x[b]; });
  PlotSeries sorted{s.name, {}, {}};
  for (std::size_t i : order) {
    sorted.x.push_back(s.x[i]);
    sorted.y.push_back(s.y[i]);
  }
  PlotParams pp;
  pp.title = "seconds per frame";
  pp.x_label = "vertices";
  pp.y_label = "seconds";
  write_png(out / "seconds_per_frame.png", line_plot(std::vector<PlotSeries>{sorted}, pp));
  std::printf("%s", md.c_str());
}

void add_bench_command(CLI::App& app) {
  auto opt = std::make_shared<BenchOptions>();
  CLI::App* sub = app.add_subcommand("bench", "Table 1 harness: track standard sequences over a range of sizes and "
                                              "report per-stage seconds and shares (JSON, Markdown, plot)");
  sub->add_option("-o,--output", opt->out, "output folder")->required();
  sub->add_option("--resolutions", opt->resolutions, "blobs resolutions (voxels across; ~1.7 res^2 vertices)")
      ->capture_default_str();
  sub->add_option("--captures", opt->captures, "resurfaced sequences from the shared data folder")->capture_default_str();
  sub->add_option("--shared", opt->shared, "the shared data folder")->capture_default_str();
  sub->add_option("--frames", opt->frames, "frames per sequence (medians over frames 2..N)")->capture_default_str();
  sub->add_option("--threads", opt->threads, "worker threads")->capture_default_str();
  sub->add_option("--profile", opt->profile, "tracker profile")->capture_default_str();
  sub->callback([opt] { run_bench(*opt); });
}

}  // namespace

TOPOTRACK_COMMAND(200, add_bench_command);

}  // namespace topotrack::cli
