// topotrack render FRAMES -o DIR: PNG pictures of frames with their colours (Embree ray tracer on the CPU),
// camera fitted to the sequence's bounds; a contact sheet of several frames; a turntable of one frame.
#include <cctype>
#include <chrono>
#include <cstdio>
#include <map>

#include <nlohmann/json.hpp>

#include "io/error.hpp"
#include "io/mapped_file.hpp"
#include "io/mesh_reader.hpp"
#include "kernels/render/png.hpp"
#include "kernels/render/raytracer.hpp"
#include "kernels/render/render_mesh.hpp"
#include "tools/cli_common.hpp"
#include "tools/commands.hpp"

namespace topotrack::cli {
namespace {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct RenderOptions {
  std::vector<std::string> inputs;
  std::string out;
  int width = 800, height = 800, samples = 2;
  bool wireframe = false;
  double wire_width = 1.0;
  double azimuth = 30, elevation = 20, fov = 30, spin = 0;
  std::string up = "y";
  std::string color;  // empty: "color" when present
  std::string fit = "all";
  int every = 1;
  int sheet = 0, sheet_size = 256, sheet_columns = 0;
  int turntable = 0;
  long turntable_frame = -1;
  bool no_frames = false;
  std::string follow;
  std::vector<std::string> diff;
  int diff_tolerance = 8;
  bool compare_ends = false;
  bool quiet = false;
};

Vec3 parse_up(const std::string& s) {
  if (s == "x") return Vec3::UnitX();
  if (s == "y") return Vec3::UnitY();
  if (s == "z") return Vec3::UnitZ();
  if (s == "-y") return -Vec3::UnitY();
  if (s == "-z") return -Vec3::UnitZ();
  TT_THROW(UsageError, "--up must be x, y, z, -y or -z");
}

//! The frame with the colours of attribute `color`, or of "color" when present if `color` is empty.
RenderMesh load_render_mesh(const fs::path& path, const std::string& color) {
  const MeshData data = read_mesh(path);
  if (!color.empty() && !data.attribute(color))
    TT_THROW(InvalidInput, path.string() << ": no vertex attribute '" << color << "' (--color)");
  try {
    return to_render_mesh(data, color.empty() ? "color" : color);
  } catch (const InvalidInput& e) {
    TT_THROW(InvalidInput, path.string() << ": " << e.what());
  }
}

struct Motion {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Vec3 center = Vec3::Zero();
};

//! Rigid motion per frame number from a ground-truth file: {"frames": [{"frame", "rotation" 3x3, "center"}]}.
std::map<long, Motion> read_motions(const fs::path& path) {
  const MappedFile file(path);
  std::map<long, Motion> out;
  try {
    const nlohmann::json j = nlohmann::json::parse(file.text());
    for (const auto& f : j.at("frames")) {
      Motion m;
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) m.rotation(r, c) = f.at("rotation").at(r).at(c).get<double>();
        m.center[r] = f.at("center").at(r).get<double>();
      }
      out[f.at("frame").get<long>()] = m;
    }
  } catch (const nlohmann::json::exception& e) {
    TT_THROW(InvalidInput, path.string() << ": not a ground-truth motion file: " << e.what());
  }
  return out;
}

//! The last run of digits in the file stem ("blobs.0048.ply" -> 48), or -1.
long number_in_name(const fs::path& path) {
  const std::string stem = path.stem().string();
  std::size_t end = stem.size();
  while (end > 0 && !std::isdigit(static_cast<unsigned char>(stem[end - 1]))) --end;
  std::size_t begin = end;
  while (begin > 0 && std::isdigit(static_cast<unsigned char>(stem[begin - 1]))) --begin;
  if (begin == end || end - begin > 15) return -1;
  return std::stol(stem.substr(begin, end - begin));
}

BoundingBox bounds_of(const RenderMesh& m) {
  BoundingBox b;
  for (const Vec3& p : m.positions) b.extend(p);
  return b;
}

//! Per-pixel difference of two pictures, over the whole image and over the pixels showing the surface in either
//! (the background colour in both left out).
void print_difference(const std::string& name_a, const Image& a, const std::string& name_b, const Image& b,
                      int tolerance) {
  CompareParams params;
  params.tolerance = tolerance;
  const ImageDifference all = compare_images(a, b, params);
  params.ignore = std::array<std::uint8_t, 3>{255, 255, 255};
  const ImageDifference fg = compare_images(a, b, params);
  std::printf("%s vs %s: mean |diff| %.3f, rms %.3f, max %d (of 255), %.2f%% pixels differ by more than %d\n",
              name_a.c_str(), name_b.c_str(), all.mean_abs, all.rms, all.max_abs, 100 * all.share_differing, tolerance);
  std::printf("surface pixels (%zu, background left out): pixel difference mean %.2f, 95th percentile %d, max %d; "
              "%.2f%% differ by more than %d\n",
              fg.pixels_compared, fg.pixel_mean, fg.pixel_p95, fg.max_abs, 100 * fg.share_differing, tolerance);
}

void run_diff(const RenderOptions& opt) {
  const Image a = read_png(opt.diff[0]);
  const Image b = read_png(opt.diff[1]);
  print_difference(opt.diff[0], a, opt.diff[1], b, opt.diff_tolerance);
}

void run_render(const RenderOptions& opt) {
  if (!opt.diff.empty()) {
    if (opt.diff.size() != 2) TT_THROW(UsageError, "--diff takes two PNG files");
    run_diff(opt);
    return;
  }
  if (opt.inputs.empty()) TT_THROW(UsageError, "FRAMES is required");
  if (opt.out.empty()) TT_THROW(UsageError, "-o OUT is required");
  if (opt.every < 1) TT_THROW(UsageError, "--every must be at least 1");
  if (opt.samples < 1 || opt.samples > 8) TT_THROW(UsageError, "--samples must be in [1, 8]");
  if (opt.sheet > 0 && (opt.sheet_size < 1 || opt.sheet_size > 16384))
    TT_THROW(UsageError, "--sheet-size must be in [1, 16384]");
  if (opt.width < 1 || opt.height < 1 || opt.width > 16384 || opt.height > 16384)
    TT_THROW(UsageError, "--width and --height must be in [1, 16384]");
  if (opt.fit != "all" && opt.fit != "each") TT_THROW(UsageError, "--fit must be all or each");
  std::vector<InputFrame> frames = resolve_frames(opt.inputs);
  {
    std::vector<InputFrame> kept;
    for (std::size_t k = 0; k < frames.size(); k += std::size_t(opt.every)) kept.push_back(frames[k]);
    frames.swap(kept);
  }
  for (auto& f : frames)
    if (f.number < 0) f.number = number_in_name(f.path);
  const fs::path out(opt.out);
  ensure_directory(out);

  RenderParams params;
  params.width = opt.width;
  params.height = opt.height;
  params.samples_per_axis = opt.samples;
  params.wireframe = opt.wireframe;
  params.wire_width_px = opt.wire_width;
  CameraFit fit;
  fit.azimuth_deg = opt.azimuth;
  fit.elevation_deg = opt.elevation;
  fit.fov_y_deg = opt.fov;
  fit.up = parse_up(opt.up);
  fit.aspect = double(opt.width) / std::max(1, opt.height);

  // One camera for the whole sequence: fitted to the union of the frames' bounds.
  BoundingBox all;
  if (opt.fit == "all") {
    for (const auto& f : frames) {
      const BoundingBox b = bounds_of(load_render_mesh(f.path, opt.color));
      if (!b.empty()) {
        all.extend(b.min);
        all.extend(b.max);
      }
    }
    if (all.empty()) TT_THROW(InvalidInput, "the frames have no vertices");
  }
  std::map<long, Motion> motions;
  if (!opt.follow.empty()) motions = read_motions(opt.follow);
  auto camera_for = [&](std::size_t k, const RenderMesh& mesh, double aspect) {
    CameraFit f = fit;
    f.aspect = aspect;
    if (frames.size() > 1) f.azimuth_deg += opt.spin * double(k) / double(frames.size() - 1);
    const Camera cam = fit_camera(opt.fit == "all" ? all : bounds_of(mesh), f);
    if (motions.empty()) return cam;
    const auto it = motions.find(frames[k].number);
    if (it == motions.end())
      TT_THROW(InvalidInput, opt.follow << ": no motion for frame " << frames[k].number);
    return transform_camera(cam, it->second.rotation, it->second.center);
  };

  double render_seconds = 0;
  std::size_t images = 0;
  Image first_image, last_image;
  if (opt.compare_ends && (opt.no_frames || frames.size() < 2))
    TT_THROW(UsageError, "--compare-ends needs at least two rendered frames (and no --no-frames)");
  if (!opt.no_frames) {
    for (std::size_t k = 0; k < frames.size(); ++k) {
      RenderMesh mesh = load_render_mesh(frames[k].path, opt.color);
      const Camera cam = camera_for(k, mesh, fit.aspect);
      RenderReport rep;
      Image im = render(std::move(mesh), cam, params, &rep);
      render_seconds += rep.build_seconds + rep.trace_seconds;
      write_png(out / frames[k].path.filename().replace_extension(".png"), im);
      ++images;
      if (k == 0) first_image = im;
      if (k + 1 == frames.size()) last_image = std::move(im);
      if (!opt.quiet) std::fprintf(stderr, "\rrender: %zu/%zu frames", k + 1, frames.size());
    }
    if (!opt.quiet) std::fprintf(stderr, "\n");
    if (opt.compare_ends)
      print_difference(frames.front().path.filename().string(), first_image, frames.back().path.filename().string(),
                       last_image, opt.diff_tolerance);
  }

  if (opt.sheet > 0) {
    const std::size_t n = std::min<std::size_t>(std::size_t(opt.sheet), frames.size());
    RenderParams tile = params;
    tile.width = tile.height = opt.sheet_size;
    std::vector<Image> tiles;
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = n == 1 ? 0 : i * (frames.size() - 1) / (n - 1);
      RenderMesh mesh = load_render_mesh(frames[k].path, opt.color);
      const Camera cam = camera_for(k, mesh, 1.0);
      RenderReport rep;
      tiles.push_back(render(std::move(mesh), cam, tile, &rep));
      render_seconds += rep.build_seconds + rep.trace_seconds;
      ++images;
    }
    ContactSheetParams sp;
    sp.columns = opt.sheet_columns;
    write_png(out / "contact_sheet.png", contact_sheet(tiles, sp));
  }

  if (opt.turntable > 0) {
    std::size_t k = 0;
    if (opt.turntable_frame >= 0) {
      k = frames.size();
      for (std::size_t i = 0; i < frames.size(); ++i)
        if (frames[i].number == opt.turntable_frame) k = i;
      if (k == frames.size()) TT_THROW(UsageError, "--turntable-frame " << opt.turntable_frame << ": no such frame");
    }
    RenderMesh mesh = load_render_mesh(frames[k].path, opt.color);
    const Camera base = camera_for(k, mesh, fit.aspect);
    const RenderScene scene(std::move(mesh));
    for (int i = 0; i < opt.turntable; ++i) {
      RenderReport rep;
      const Image im = render(scene, orbit(base, fit.up, 360.0 * i / opt.turntable), params, &rep);
      render_seconds += rep.trace_seconds;
      char name[64];
      std::snprintf(name, sizeof name, "turntable.%04d.png", i);
      write_png(out / name, im);
      ++images;
    }
  }
  std::printf("rendered %zu images (%dx%d, %d samples per pixel) into %s: %.3f s rendering, %.3f s per image\n", images,
              params.width, params.height, opt.samples * opt.samples, out.string().c_str(), render_seconds,
              images ? render_seconds / images : 0.0);
}

void add_render_command(CLI::App& app) {
  auto opt = std::make_shared<RenderOptions>();
  CLI::App* sub = app.add_subcommand(
      "render", "Ray-trace frames to PNG with their vertex colours (camera fitted to the sequence), a contact sheet "
                "and a turntable; --diff A.png B.png compares two images");
  sub->add_option("FRAMES", opt->inputs, "mesh files, folders, globs or frame patterns");
  sub->add_option("-o,--output", opt->out, "output folder");
  sub->add_option("--width", opt->width, "image width")->capture_default_str();
  sub->add_option("--height", opt->height, "image height")->capture_default_str();
  sub->add_option("--samples", opt->samples, "supersampling: N x N rays per pixel (1..8)")->capture_default_str();
  sub->add_flag("--wireframe", opt->wireframe, "draw the triangle edges");
  sub->add_option("--wire-width", opt->wire_width, "edge width in pixels")->capture_default_str();
  sub->add_option("--azimuth", opt->azimuth, "camera azimuth about the up axis, degrees")->capture_default_str();
  sub->add_option("--elevation", opt->elevation, "camera elevation, degrees")->capture_default_str();
  sub->add_option("--fov", opt->fov, "vertical field of view, degrees")->capture_default_str();
  sub->add_option("--up", opt->up, "up axis: x, y, z, -y, -z")->capture_default_str();
  sub->add_option("--spin", opt->spin, "the camera turns by this many degrees from the first to the last frame")
      ->capture_default_str();
  sub->add_option("--follow", opt->follow,
                  "ground-truth motion file (gen's ground_truth.json): the camera moves rigidly with each frame");
  sub->add_option("--fit", opt->fit, "camera fitted to all frames' bounds or each frame's")->capture_default_str();
  sub->add_option("--color", opt->color, "vertex attribute with the colours (default: `color` when present)");
  sub->add_option("--every", opt->every, "render every n-th frame")->capture_default_str();
  sub->add_flag("--no-frames", opt->no_frames, "no per-frame images (only the sheet / turntable)");
  sub->add_option("--sheet", opt->sheet, "contact sheet of N evenly spaced frames (contact_sheet.png)");
  sub->add_option("--sheet-size", opt->sheet_size, "tile size of the contact sheet")->capture_default_str();
  sub->add_option("--sheet-columns", opt->sheet_columns, "columns of the contact sheet (default: square)");
  sub->add_option("--turntable", opt->turntable, "N views around one frame (turntable.NNNN.png)");
  sub->add_option("--turntable-frame", opt->turntable_frame, "frame number of the turntable (default: first)");
  sub->add_option("--diff", opt->diff, "compare two PNG images per pixel instead of rendering")->expected(2);
  sub->add_option("--diff-tolerance", opt->diff_tolerance, "channel difference counted as differing")
      ->capture_default_str();
  sub->add_flag("--compare-ends", opt->compare_ends,
                "compare the first and the last rendered frame per pixel (with --follow: does a texture stick?)");
  sub->add_flag("-q,--quiet", opt->quiet, "no progress line");
  sub->callback([opt] { run_render(*opt); });
}

}  // namespace

TOPOTRACK_COMMAND(120, add_render_command);

}  // namespace topotrack::cli
