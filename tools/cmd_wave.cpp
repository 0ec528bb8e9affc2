// topotrack wave FRAMES -o OUT: the topology-aware wave simulation of §5 (eq. 1) on a tracked sequence; writes
// the frames displaced along their normals by the wave height (attribute `height`), events copied, wave.json.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "io/ply_writer.hpp"
#include "kernels/propagate/frame_geometry.hpp"
#include "kernels/propagate/tracked_sequence.hpp"
#include "kernels/wave/wave.hpp"
#include "tools/cli_common.hpp"
#include "tools/commands.hpp"

namespace topotrack::cli {
namespace {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct WaveOptions {
  std::vector<std::string> inputs;
  std::string out;
  double speed = 0;       // <= 0: two mean edge lengths per frame
  double fps = 30;
  int substeps = 0;
  double damping = 0;
  double inject = 0.5;    // mean edge lengths
  double inject_velocity = 0;
  double scale = 1;
  bool quiet = false;
};

double mean_edge(const FrameGeometry& g) {
  double sum = 0;
  std::size_t n = 0;
  for (const auto& t : g.triangles)
    for (int k = 0; k < 3; ++k) {
      sum += (g.positions[t[k]] - g.positions[t[(k + 1) % 3]]).norm();
      ++n;
    }
  return n ? sum / n : 0.0;
}

void run_wave(const WaveOptions& opt) {
  const auto t_start = Clock::now();
  if (!(opt.fps > 0)) TT_THROW(UsageError, "--fps must be positive");
  if (opt.substeps < 0) TT_THROW(UsageError, "--substeps must be >= 0 (0: from the CFL bound)");
  if (!(opt.damping >= 0 && opt.damping < 1)) TT_THROW(UsageError, "--damping must be in [0, 1)");
  if (!(opt.speed >= 0) || !std::isfinite(opt.speed)) TT_THROW(UsageError, "--speed must be >= 0 (0: automatic)");
  const std::vector<TrackedFrame> frames = resolve_tracked_frames(opt.inputs);
  const fs::path out(opt.out);
  ensure_directory(out);

  WaveParams params;
  params.frame_time = 1.0 / opt.fps;
  params.substeps = opt.substeps;
  params.damping = opt.damping;
  WaveState state;
  nlohmann::json log = nlohmann::json::array();
  double sim_seconds = 0;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    FrameFile frame = read_frame_file(frames[k].mesh, true);
    MeshData& data = frame.data;
    const FrameGeometry& g = frame.geometry;
    if (k == 0) {
      const double L = mean_edge(g);
      params.speed = opt.speed > 0 ? opt.speed : 2 * L * opt.fps;
      params.inject_height = opt.inject * L;
      params.inject_velocity = opt.inject_velocity * L;
    }
    const auto t0 = Clock::now();
    WaveReport rep;
    if (k == 0)
      state = zero_wave_state(g.ids);
    else
      state = transfer_wave_state(state, load_frame_events(frames, k), g.ids, params, &rep);
    integrate_waves(g.positions, g.triangles, state, params, &rep);
    const std::vector<Vec3> moved = displace_along_normals(g.positions, g.triangles, state.h, opt.scale);
    sim_seconds += std::chrono::duration<double>(Clock::now() - t0).count();
    set_positions(data, moved);
    set_attribute(data, "height", 1, std::vector<float>(state.h.begin(), state.h.end()));
    write_ply(out / frames[k].mesh.filename().replace_extension(".ply"), data);
    if (k > 0 && fs::exists(frames[k].events))
      fs::copy_file(frames[k].events, out / frames[k].events.filename(), fs::copy_options::overwrite_existing);
    log.push_back({{"frame", frames[k].number},
                   {"vertices", g.positions.size()},
                   {"substeps", rep.substeps},
                   {"dt", rep.dt},
                   {"injected", rep.injected},
                   {"missing", rep.missing},
                   {"energy_before", rep.energy_before},
                   {"energy_after", rep.energy_after},
                   {"max_abs_height", rep.max_abs_height},
                   {"seconds", {{"transfer", rep.transfer_seconds},
                                {"laplacian", rep.laplacian_seconds},
                                {"integrate", rep.integrate_seconds}}}});
    if (!opt.quiet)
      std::fprintf(stderr, "\rwave: %zu/%zu frames, %d sub-steps, energy %.3g, %zu injected   ", k + 1, frames.size(),
                   rep.substeps, rep.energy_after, rep.injected);
  }
  if (!opt.quiet) std::fprintf(stderr, "\n");
  const nlohmann::json summary = {{"speed", params.speed},
                                  {"frame_time", params.frame_time},
                                  {"damping", params.damping},
                                  {"inject_height", params.inject_height},
                                  {"inject_velocity", params.inject_velocity},
                                  {"frames", log}};
  write_file_atomic(out / "wave.json", summary.dump(2) + "\n");
  std::printf("wave: %zu frames into %s, c = %.4g, %.3f s simulating, %.3f s total\n", frames.size(),
              out.string().c_str(), params.speed, sim_seconds,
              std::chrono::duration<double>(Clock::now() - t_start).count());
}

void add_wave_command(CLI::App& app) {
  auto opt = std::make_shared<WaveOptions>();
  CLI::App* sub = app.add_subcommand(
      "wave", "Wave simulation on a tracked sequence (§5, eq. 1): energy injected only where topology changed; "
              "writes the frames displaced by the wave height");
  sub->add_option("FRAMES", opt->inputs, "tracked frames (topotrack track output)")->required();
  sub->add_option("-o,--output", opt->out, "output folder")->required();
  sub->add_option("--speed", opt->speed, "wave speed c in scene units per second (default: 2 mean edge lengths per "
                                         "frame)");
  sub->add_option("--fps", opt->fps, "frames per second")->capture_default_str();
  sub->add_option("--substeps", opt->substeps, "symplectic Euler steps per frame (default: from the CFL bound)");
  sub->add_option("--damping", opt->damping, "epsilon: h *= 1 - epsilon per step (the paper used 0)")
      ->capture_default_str();
  sub->add_option("--inject", opt->inject, "height added where a topology patch creates a vertex, in mean edge "
                                           "lengths of the first frame")
      ->capture_default_str();
  sub->add_option("--inject-velocity", opt->inject_velocity, "normal velocity added there, mean edge lengths / s")
      ->capture_default_str();
  sub->add_option("--scale", opt->scale, "displacement = scale * height along the normal")->capture_default_str();
  sub->add_flag("-q,--quiet", opt->quiet, "no progress line");
  sub->callback([opt] { run_wave(*opt); });
}

}  // namespace

TOPOTRACK_COMMAND(100, add_wave_command);

}  // namespace topotrack::cli
