// topotrack track INPUT -o OUT: Algorithm 1 over a sequence, one frame at a time, with per-stage timings,
// a progress display and --resume after a crash. Pipelined (issue #6): frame n+1 is read and prepared
// (Tracker::prepare: its scene and φ_S) and frame n-1 written while frame n is tracked, on the one TBB pool.
#include <sys/resource.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <chrono>
#include <cmath>
#include <exception>
#include <nlohmann/json.hpp>
#include <optional>

#include "engine/checkpoint.hpp"
#include "engine/frame_loader.hpp"
#include "engine/tracker.hpp"
#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "io/event_file.hpp"
#include "io/mesh_reader.hpp"
#include "io/mapped_file.hpp"
#include "io/ply_writer.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/raycast/embree_scene.hpp"
#include "tools/cli_common.hpp"
#include "tools/commands.hpp"
#include "tools/heap.hpp"
#include "tools/progress.hpp"

namespace topotrack::cli {
namespace {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct TrackOptions {
  std::string input;
  std::string out;
  std::string profile = "default";
  std::vector<std::string> settings;
  int threads = 0;
  int every = 1;
  bool resume = false;
  std::string progress = "auto";
  bool quiet = false;
  double edge_length = -1;
  double graph_density = -1;
  bool no_coarse = false, no_fine = false, no_topology = false, projection_only = false;
  bool close_holes = false;
  double max_hole = FrameLoadParams{}.max_hole_voxels;
  std::string name;
  bool no_pipeline = false;
};

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

double peak_memory_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

std::string frame_file(const TrackOptions& opt, long number, const char* ext) {
  char buf[32];
  std::snprintf(buf, sizeof buf, ".%04ld", number);
  return opt.name + buf + ext;
}

nlohmann::json frame_json(const FrameReport& r, long number, double io_seconds, double wall_seconds) {
  nlohmann::json ev = nlohmann::json::object();
  for (int k = 1; k <= kEventKindCount; ++k)
    ev[std::string(to_string(EventKind(k)))] = r.events_by_kind.size() >= std::size_t(k) ? r.events_by_kind[k - 1] : 0;
  return {{"frame", number},
          {"index", r.index},
          {"vertices", r.vertices},
          {"triangles", r.triangles},
          {"components", r.components},
          {"euler", r.euler},
          {"events", ev},
          {"complex_cells", {{"self", r.complex_cells_self}, {"target", r.complex_cells_target}}},
          {"complex_by_reason",
           {{"self", complex_reasons_json(r.complex_reasons_self)}, {"target", complex_reasons_json(r.complex_reasons_target)}}},
          {"topology_failures", r.topology_failures},
          {"small_components", {{"added", r.small_components_added}, {"removed", r.small_components_removed}}},
          {"topology_refinement",
           {{"retries", r.topology_retries},
            {"level", r.topology_level},
            {"rejected_for_quality", r.topology_rejected_for_quality}}},
          {"warnings", r.warnings},
          {"iterations", {{"coarse", r.coarse_iterations}, {"coarse_pass", r.coarse_pass_iterations},
                          {"fine_cg", r.fine_iterations}, {"fine_rounds", r.fine_rounds}, {"relax", r.relax_iterations}}},
          {"seconds",
           {{"coarse", r.seconds.coarse},
            {"fine", r.seconds.fine},
            {"improve", r.seconds.improve},
            {"signed_distance", r.seconds.signed_distance},
            {"topology", r.seconds.topology},
            {"prepare", r.seconds.prepare},
            {"io", io_seconds},
            {"total", r.seconds.total + io_seconds},
            {"wall", wall_seconds}}},
          {"peak_memory_mb", peak_memory_mb()}};
}

//! The tracked mesh as written: x y z, persistent id, velocity (vx vy vz) per vertex.
MeshData output_mesh(const Tracker& tracker) {
  MeshData d = to_mesh_data(tracker.mesh(), /*with_properties=*/false);
  VertexAttribute v{"v", 3, {}};
  v.values.reserve(3 * d.vertex_count());
  const auto& vel = tracker.velocities();
  for (Index i = 0; i < tracker.mesh().vertices_size(); ++i) {
    if (tracker.mesh().is_deleted(Vertex(i))) continue;
    for (int c = 0; c < 3; ++c) v.values.push_back(float(vel[i][c]));
  }
  d.attributes.push_back(std::move(v));
  return d;
}

//! Frame n read from disk and prepared for the tracker, possibly while frame n-1 was tracked. Errors are
//! kept, to be raised when the loop reaches the frame: after every frame before it is written.
struct ReadFrame {
  FrameLoadReport load;
  PreparedFrame prepared;
  double io_seconds = 0;
  std::exception_ptr load_error, prepare_error;
};

ReadFrame read_frame(const InputFrame& f, const FrameLoadParams& params, const Tracker& tracker) {
  ReadFrame r;
  const auto t0 = Clock::now();
  LoadedFrame frame;
  try {
    frame = load_frame(f.path, params);
  } catch (...) {
    r.load_error = std::current_exception();
    return r;
  }
  r.io_seconds = since(t0);
  r.load = std::move(frame.report);
  try {
    const std::string name = f.path.string();
    r.prepared = frame.grid ? tracker.prepare(*frame.grid, name) : tracker.prepare(std::move(frame.mesh), name);
  } catch (...) {
    r.prepare_error = std::current_exception();
  }
  return r;
}

//! Frame n's outputs, copied from the tracker so that they can be written while frame n+1 is tracked.
struct FrameOutput {
  std::size_t index = 0;
  long number = 0;
  std::string input;
  MeshData mesh;
  EventList events;
  Checkpoint checkpoint;
  FrameReport report;
  FrameLoadReport load;
  double io_seconds = 0, wall_seconds = 0;
  std::string summary, json;  // for the progress display, set by write_output
};

//! The track.json being built and where the frame files go.
struct OutputSink {
  const TrackOptions& opt;
  fs::path out, json_path, checkpoint_path;
  nlohmann::json report;
};

//! Write frame n's PLY and events, then track.json, then (last: it marks the frame complete, its files all
//! in place) the checkpoint. Each file is written atomically, so a killed run never shows a partial frame.
void write_output(FrameOutput& o, OutputSink& sink) {
  const auto t0 = Clock::now();
  write_ply(sink.out / frame_file(sink.opt, o.number, ".ply"), o.mesh);
  write_events(sink.out / frame_file(sink.opt, o.number, ".events"), o.events);
  o.io_seconds += since(t0);
  const FrameReport& r = o.report;
  nlohmann::json fj = frame_json(r, o.number, o.io_seconds, o.wall_seconds);
  fj["input"] = o.input;
  if (o.load.holes_closed > 0) {
    fj["input_repair"] = {{"holes_closed", o.load.holes_closed},
                          {"hole_boundary_edges", o.load.hole_boundary_edges},
                          {"largest_hole", o.load.largest_hole},
                          {"voxel_size", o.load.voxel_size}};
    for (const auto& w : o.load.warnings) fj["warnings"].push_back(w);
  }
  sink.report["frames"].push_back(fj);
  sink.report["edge_length"] = o.checkpoint.target_edge_length;
  sink.report["voxel_size"] = o.checkpoint.voxel_size;
  const Vec3& origin = o.checkpoint.lattice_origin;
  sink.report["lattice_origin"] = {origin.x(), origin.y(), origin.z()};
  write_file_atomic(sink.json_path, sink.report.dump(1) + "\n");
  write_checkpoint(sink.checkpoint_path, o.checkpoint);
  char summary[160];
  std::snprintf(summary, sizeof summary, "%zu verts, %zu comps, %zu events, %.2fs", r.vertices, r.components,
                o.events.size(), r.seconds.total + o.io_seconds);
  o.summary = summary;
  o.json = fj.dump();
}

void run_track(TrackOptions opt) {
  keep_large_blocks_unpooled();
  if (opt.every < 1) TT_THROW(UsageError, "--every must be at least 1");
  if (opt.threads < 0) TT_THROW(UsageError, "--threads must be at least 1");
  std::unique_ptr<tbb::global_control> threads;
  if (opt.threads > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, opt.threads);

  TrackerParams params = load_profile(opt.profile);
  if (opt.edge_length >= 0) params.edge_length = opt.edge_length;
  if (opt.graph_density > 0) params.coarse_params.graph_density = opt.graph_density;
  if (opt.no_coarse) params.coarse = false;
  if (opt.no_fine) params.fine = false;
  if (opt.no_topology) params.topology = false;
  if (opt.projection_only) params.projection_only = true;
  for (const auto& s : opt.settings) apply_setting(params, s);
  validate(params);

  if (!(opt.max_hole > 0)) TT_THROW(UsageError, "--max-hole must be positive");

  std::vector<std::string> warnings;
  std::vector<InputFrame> all = resolve_inputs({opt.input}, &warnings);
  std::vector<InputFrame> frames;
  for (std::size_t i = 0; i < all.size(); i += std::size_t(opt.every)) frames.push_back(all[i]);
  if (frames.empty()) TT_THROW(InvalidInput, opt.input << ": no frames");
  for (std::size_t i = 0; i < frames.size(); ++i)
    if (frames[i].number < 0) frames[i].number = long(i + 1);
  if (opt.name.empty()) opt.name = sequence_name(frames.front().path);
  if (opt.close_holes && params.edge_length <= 0 && frames.front().path.extension() != ".vdb") {
    // L from the first frame as read, before any hole is closed (closing resamples it at the voxel size),
    // so that every frame is closed at the same voxel size, the tracker's (§4.3).
    params.edge_length = soup_mean_edge_length(read_mesh(frames.front().path));
    validate(params);
  }
  FrameLoadParams load_params;
  load_params.close_holes = opt.close_holes;
  load_params.max_hole_voxels = opt.max_hole;

  const fs::path out(opt.out);
  // Never overwrite the input: the output frames carry the input's name, so OUT may not be the input's folder.
  for (const InputFrame& f : frames)
    if (fs::weakly_canonical(out / frame_file(opt, f.number, ".ply")) == fs::weakly_canonical(f.path))
      TT_THROW(UsageError, opt.out << ": the output would overwrite the input frame " << f.path.string()
                                   << " (choose another -o or --name)");
  ensure_directory(out);
  const fs::path checkpoint_path = out / "track.checkpoint";
  const fs::path json_path = out / "track.json";
  const nlohmann::json params_json = to_json(params);

  Progress progress(opt.quiet ? ProgressMode::Quiet : parse_progress_mode(opt.progress), frames.size());
  for (const auto& w : warnings) progress.message("warning: " + w);

  Tracker tracker(params);
  OutputSink sink{opt, out, json_path, checkpoint_path, {}};
  nlohmann::json& report = sink.report;
  report = {{"version", 1},
            {"input", opt.input},
            {"name", opt.name},
            {"profile", opt.profile},
            {"parameters", params_json},
            {"threads", opt.threads},
            {"embree_isa", embree_isa()},
            {"every", opt.every},
            {"frames", nlohmann::json::array()}};
  std::size_t start = 0;
  if (opt.resume && fs::exists(checkpoint_path)) {
    Checkpoint c = read_checkpoint(checkpoint_path);
    const MappedFile prior(json_path);
    nlohmann::json old;
    try {
      old = nlohmann::json::parse(prior.text());
    } catch (const nlohmann::json::exception& e) {
      TT_THROW(InvalidInput, json_path.string() << ": cannot resume, not valid JSON: " << e.what());
    }
    if (old.value("parameters", nlohmann::json()) != params_json || old.value("every", 1) != opt.every)
      TT_THROW(UsageError, out.string() << ": cannot resume with different parameters than the interrupted run "
                                        << "(see " << (out / "profile.json").string() << ")");
    if (c.frame_index < 0 || std::size_t(c.frame_index) >= frames.size() ||
        frames[std::size_t(c.frame_index)].number != c.frame_number)
      TT_THROW(InvalidInput, checkpoint_path.string() << ": frame " << c.frame_number
                                                      << " is not in this input sequence");
    if (old.value("embree_isa", std::string(embree_isa())) != embree_isa())
      progress.message("warning: " + json_path.string() + ": the interrupted run used Embree's " +
                       old.value("embree_isa", std::string()) + " kernels, this one " + embree_isa() +
                       ": the frames from here on can differ slightly from an uninterrupted run's");
    start = std::size_t(c.frame_index) + 1;
    for (const auto& f : old["frames"])
      if (f.value("index", std::size_t(0)) < start) report["frames"].push_back(f);
    tracker.restore(std::move(c.mesh), start, c.target_edge_length, c.voxel_size, c.lattice_origin);
    progress.message("resuming after frame " + std::to_string(c.frame_number));
  } else if (opt.resume) {
    progress.message("nothing to resume in " + out.string() + ": starting from the first frame");
  }
  write_file_atomic(out / "profile.json", params_json.dump(2) + "\n");

  // The pipeline (issue #6): while frame i is tracked on this thread, one task reads and prepares frame
  // i+1 and another writes frame i-1, on the same TBB pool (--threads bounds all of it). At most one frame
  // is read ahead. The tracker itself stays sequential (Algorithm 1), so the output is the same as
  // without the pipeline, bit for bit; messages and errors of a frame come when the loop reaches it,
  // after every frame before it is written, as they would one frame at a time.
  auto load_params_now = [&] {
    FrameLoadParams p = load_params;
    p.voxel_size = tracker.frames() > 0 ? tracker.voxel_size() : first_voxel_size(params, params.edge_length);
    return p;
  };
  tbb::task_group tasks;
  auto spawn = [&](auto&& job) {
    if (opt.no_pipeline) job();
    else tasks.run(std::forward<decltype(job)>(job));
  };
  std::optional<FrameOutput> pending;  // the last tracked frame, until it is written
  // Written, the frame is complete (its checkpoint too): said at once, from the writing task if need be.
  auto write_pending = [&] {
    write_output(*pending, sink);
    progress.frame_done(pending->index, pending->number, pending->summary, pending->json);
  };
  // Also after an error: the tasks finish first (an earlier frame's write error is the one to report).
  auto drain = [&] { tasks.wait(); };

  std::optional<ReadFrame> next;
  if (start < frames.size()) next = read_frame(frames[start], load_params_now(), tracker);
  auto last_done = Clock::now();
  for (std::size_t i = start; i < frames.size(); ++i) {
    const InputFrame& f = frames[i];
    ReadFrame cur = std::move(*next);
    next.reset();
    if (pending) spawn(write_pending);
    if (cur.load_error) {
      drain();
      progress.stage(i, f.number, "reading");
      std::rethrow_exception(cur.load_error);
    }
    const bool ahead = i + 1 < frames.size() && tracker.frames() > 0;  // the voxel size is fixed
    if (ahead) spawn([&next, &tracker, g = frames[i + 1], p = load_params_now()] { next = read_frame(g, p, tracker); });
    progress.stage(i, f.number, "reading");
    for (const auto& w : cur.load.warnings) progress.message("warning: frame " + std::to_string(f.number) + ": " + w);
    progress.stage(i, f.number, "tracking");
    const FrameReport* r = nullptr;
    try {
      if (cur.prepare_error) std::rethrow_exception(cur.prepare_error);
      // Isolated: while its own parallel loops wait, this thread takes no read or write task, so the
      // frame on the critical path is never held up by one.
      tbb::this_task_arena::isolate([&] { r = &tracker.add_frame(std::move(cur.prepared)); });
    } catch (...) {
      drain();
      throw;
    }
    drain();
    pending.reset();
    if (i + 1 < frames.size() && !ahead) next = read_frame(frames[i + 1], load_params_now(), tracker);

    for (const auto& w : r->warnings) progress.message("warning: frame " + std::to_string(f.number) + ": " + w);
    progress.stage(i, f.number, "writing");
    const auto now = Clock::now();
    FrameOutput& o = pending.emplace();
    o.index = i;
    o.number = f.number;
    o.input = f.path.string();
    o.mesh = output_mesh(tracker);
    o.events = tracker.take_events();  // moved: the writer runs beside the next frame
    o.checkpoint = {f.number, long(i), tracker.edge_length(), tracker.voxel_size(), tracker.mesh().clone(),
                    tracker.lattice_origin()};
    o.report = *r;
    o.load = std::move(cur.load);
    o.io_seconds = cur.io_seconds;
    o.wall_seconds = std::chrono::duration<double>(now - last_done).count();
    last_done = now;
  }
  if (pending) write_pending();
  progress.finish("tracked " + std::to_string(frames.size()) + " frames into " + out.string());
}

void add_track_command(CLI::App& app) {
  auto opt = std::make_shared<TrackOptions>();
  CLI::App* sub = app.add_subcommand("track", "Track a sequence of closed surfaces into one temporally coherent "
                                              "mesh (Algorithm 1): OUT/<name>.<n>.ply, .events, track.json");
  sub->add_option("INPUT", opt->input, "folder, glob or frame pattern of OBJ, PLY or .vdb frames")->required();
  sub->add_option("-o,--output", opt->out, "output folder")->required();
  sub->add_option("--profile", opt->profile, "bundled profile name or a .json file (default: the paper's values)");
  sub->add_option("--set", opt->settings, "override one parameter, e.g. --set coarse.alpha_reg_start=100");
  sub->add_option("--threads", opt->threads, "worker threads (default: all cores)");
  sub->add_option("--every", opt->every, "track every K-th input frame");
  sub->add_flag("--resume", opt->resume, "continue after the last complete frame of an interrupted run");
  sub->add_option("--progress", opt->progress, "auto, bar, lines, jsonl or quiet");
  sub->add_flag("--quiet", opt->quiet, "no progress output");
  sub->add_option("--edge-length", opt->edge_length, "target edge length L (default: mean of the first frame)");
  sub->add_option("--graph-density", opt->graph_density, "deformation graph density: 1, 0.5, 0.25 (§6 preview)");
  sub->add_flag("--no-coarse", opt->no_coarse, "ablation: skip the coarse alignment (§6)");
  sub->add_flag("--no-fine", opt->no_fine, "ablation: skip the fine alignment (§6, Fig. 8)");
  sub->add_flag("--no-topology", opt->no_topology, "ablation: skip the topology constraint (§6)");
  sub->add_flag("--projection-only", opt->projection_only, "ablation: project onto the closest point (Fig. 9)");
  sub->add_flag("--close-holes", opt->close_holes,
                "close small holes of open input surfaces through the level set (docs/robustness.md)");
  sub->add_option("--max-hole", opt->max_hole, "largest hole --close-holes closes, in voxels across (default 8)");
  sub->add_option("--name", opt->name, "output file name prefix (default: from the input)");
  sub->add_flag("--no-pipeline", opt->no_pipeline,
                "read, track and write one frame at a time, without overlapping them (for measurements)");
  sub->callback([opt] { run_track(*opt); });
}

}  // namespace

TOPOTRACK_COMMAND(40, add_track_command);

}  // namespace topotrack::cli
