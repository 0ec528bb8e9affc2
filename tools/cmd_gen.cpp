// topotrack gen KIND -o DIR: synthetic input sequences with ground truth (blobs, morph, metaballs, splash) or a
// coherent sequence re-meshed through a level set (resurface SRC). The work is in kernels/gen.
#include <cstdio>
#include <iostream>
#include <memory>

#include "kernels/gen/gen_sequence.hpp"
#include "tools/cli_common.hpp"
#include "tools/commands.hpp"
#include "tools/progress.hpp"

namespace topotrack::cli {
namespace {

struct GenOptions {
  GenParams params;
  std::string out;
  std::string progress = "auto";
};

void run_gen(GenOptions& opt) {
  if (opt.params.kind == "resurface" && opt.params.source.empty())
    throw UsageError("gen resurface: missing SRC (a folder, glob or frame pattern of a coherent sequence)");
  if (opt.params.kind != "resurface" && !opt.params.source.empty())
    throw UsageError("gen " + opt.params.kind + ": unexpected argument '" + opt.params.source + "'");
  const ProgressMode mode = parse_progress_mode(opt.progress);
  ensure_directory(opt.out);
  std::unique_ptr<Progress> progress;
  opt.params.progress = [&](const GenFrameReport& r, int total) {
    if (!progress) progress = std::make_unique<Progress>(mode, std::size_t(total));
    char summary[160];
    std::snprintf(summary, sizeof summary, "%s: %zu vertices, %zu triangles, %ld components, genus %ld, %.2f s",
                  r.file.c_str(), r.vertices, r.triangles, r.components, r.genus, r.seconds);
    char json[256];
    std::snprintf(json, sizeof json,
                  "{\"frame\":%d,\"vertices\":%zu,\"triangles\":%zu,\"components\":%ld,\"genus\":%ld,\"seconds\":%.4f}",
                  r.frame, r.vertices, r.triangles, r.components, r.genus, r.seconds);
    progress->frame_done(std::size_t(r.frame - 1), r.frame, summary, json);
  };
  const GenReport report = generate_sequence(opt.params, opt.out);
  char done[200];
  std::snprintf(done, sizeof done, "wrote %zu %s frames (resolution %d, voxel size %.6g) to %s in %.2f s",
                report.frames.size(), report.kind.c_str(), report.resolution, report.voxel_size, opt.out.c_str(),
                report.seconds);
  if (progress) progress->finish(done);
}

void add_gen_command(CLI::App& app) {
  auto opt = std::make_shared<GenOptions>();
  CLI::App* sub = app.add_subcommand(
      "gen", "Generate an input sequence with ground truth: blobs, morph, metaballs, splash, or resurface SRC");
  sub->add_option("KIND", opt->params.kind, "blobs | morph | metaballs | splash | resurface")
      ->required()
      ->check(CLI::IsMember({"blobs", "morph", "metaballs", "splash", "resurface"}));
  sub->add_option("SRC", opt->params.source, "resurface: the coherent source sequence (folder, glob or pattern)");
  sub->add_option("-o,--output", opt->out, "output folder")->required();
  sub->add_option("--frames", opt->params.frames, "number of frames (default 60; resurface: all source frames)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--last", opt->params.last_frame,
                  "synthetic kinds: write only frames 1..N of the --frames sequence (default: all)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--resolution", opt->params.resolution,
                  "voxels across the bounding box (default: ~10-20k vertices; resurface 128)")
      ->check(CLI::Range(0, 4096));
  sub->add_option("--start", opt->params.start, "resurface: first source frame number");
  sub->add_option("--every", opt->params.every, "resurface: use every n-th source frame")->check(CLI::PositiveNumber);
  sub->add_option("--grid-offset", opt->params.grid_offset,
                  "resurface: the grid's nodes at (X + i, Y + j, Z + k) voxels, each in [0, 1) (default 0,0,0)")
      ->delimiter(',');
  sub->add_option("--seed", opt->params.seed, "perturbs the synthetic shapes (deterministic)");
  sub->add_option("--progress", opt->progress, "auto | bar | lines | jsonl | quiet");
  sub->callback([opt] { run_gen(*opt); });
}

}  // namespace

TOPOTRACK_COMMAND(20, add_gen_command);

}  // namespace topotrack::cli
