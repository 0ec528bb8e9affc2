// topotrack propagate FRAMES -o OUT: carry a per-vertex attribute through a tracked sequence's event lists
// (§4.6) forward and/or backward from a frame; colour and displacement maps and the colour morph of §5.
#include <chrono>
#include <cstdio>
#include <sstream>

#include "io/error.hpp"
#include "io/mesh_reader.hpp"
#include "io/ply_writer.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/propagate/frame_geometry.hpp"
#include "kernels/propagate/image_projection.hpp"
#include "kernels/propagate/patterns.hpp"
#include "kernels/propagate/tracked_sequence.hpp"
#include "kernels/render/png.hpp"
#include "kernels/wave/laplacian.hpp"
#include "tools/cli_common.hpp"
#include "tools/commands.hpp"

namespace topotrack::cli {
namespace {
namespace fs = std::filesystem;

struct PropagateOptions {
  std::vector<std::string> inputs;
  std::string out;
  bool in_place = false;
  long from = -1;
  std::string direction = "forward";
  std::string source = "checker";
  std::string morph_source;
  std::string name;
  std::string fallback;
  double displace = 0;
  bool round_trip = false;
  bool quiet = false;
};

// "kind:key=value,key=value" -> kind and the pairs.
struct SourceSpec {
  std::string kind;
  std::vector<std::pair<std::string, std::string>> keys;
  const std::string* get(const std::string& k) const {
    for (const auto& [key, value] : keys)
      if (key == k) return &value;
    return nullptr;
  }
};

SourceSpec parse_spec(const std::string& text) {
  SourceSpec s;
  const auto colon = text.find(':');
  s.kind = text.substr(0, colon);
  if (colon != std::string::npos) {
    std::stringstream ss(text.substr(colon + 1));
    std::string item;
    while (std::getline(ss, item, ',')) {
      const auto eq = item.find('=');
      if (eq == std::string::npos || eq == 0) TT_THROW(UsageError, "source '" << text << "': expected key=value, got '" << item << "'");
      s.keys.emplace_back(item.substr(0, eq), item.substr(eq + 1));
    }
  }
  return s;
}

double to_double(const std::string& v, const std::string& what) {
  try {
    std::size_t used = 0;
    const double d = std::stod(v, &used);
    if (used != v.size() || !std::isfinite(d)) throw std::invalid_argument(v);
    return d;
  } catch (const std::exception&) {
    TT_THROW(UsageError, what << ": '" << v << "' is not a number");
  }
}

std::vector<float> to_floats(const std::string& v, const std::string& what) {
  std::vector<float> out;
  std::stringstream ss(v);
  std::string item;
  while (std::getline(ss, item, '/')) out.push_back(float(to_double(item, what)));
  if (out.empty()) TT_THROW(UsageError, what << ": no values");
  return out;
}

Vec3 to_vec3(const std::string& v, const std::string& what) {
  if (v == "x") return Vec3::UnitX();
  if (v == "y") return Vec3::UnitY();
  if (v == "z") return Vec3::UnitZ();
  const auto f = to_floats(v, what);
  if (f.size() != 3) TT_THROW(UsageError, what << ": expected x, y, z or three values a/b/c");
  return Vec3(f[0], f[1], f[2]);
}

//! The source's values on a frame, width per vertex.
IdField evaluate_source(const SourceSpec& spec, const MeshData& data, const FrameGeometry& g, const fs::path& file) {
  IdField field;
  field.ids = g.ids;
  if (spec.kind == "attribute") {
    const std::string* name = spec.get("name");
    const std::string attr = name ? *name : "color";
    const VertexAttribute* a = data.attribute(attr);
    if (!a) TT_THROW(InvalidInput, file.string() << ": no vertex attribute '" << attr << "'");
    field.width = a->width;
    field.values = a->values;
    return field;
  }
  if (spec.kind == "image") {
    const std::string* path = spec.get("file");
    if (!path) TT_THROW(UsageError, "source image: needs file=PATH");
    const Image image = read_png(*path);
    BoundingBox box;
    for (const Vec3& p : g.positions) box.extend(p);
    CameraFit fit;
    fit.aspect = double(image.width) / image.height;
    fit.margin = 1.0;
    if (const auto* v = spec.get("azimuth")) fit.azimuth_deg = to_double(*v, "azimuth");
    if (const auto* v = spec.get("elevation")) fit.elevation_deg = to_double(*v, "elevation");
    if (const auto* v = spec.get("up")) fit.up = to_vec3(*v, "up");
    const Camera cam = fit_camera(box, fit);
    const float grey[3] = {0.5f, 0.5f, 0.5f};
    field.width = 3;
    field.values = project_image(g.positions, image, cam, grey);
    return field;
  }
  PatternParams p;
  if (spec.kind == "constant") {
    p.kind = PatternKind::Constant;
    const std::string* v = spec.get("value");
    p.a = v ? to_floats(*v, "value") : std::vector<float>{1.0f, 1.0f, 1.0f};
    p.b = p.a;
  } else {
    p.kind = parse_pattern_kind(spec.kind);
    if (const auto* v = spec.get("a")) p.a = to_floats(*v, "a");
    if (const auto* v = spec.get("b")) p.b = to_floats(*v, "b");
    if (const auto* v = spec.get("cell")) p.cell = to_double(*v, "cell");
    if (const auto* v = spec.get("axis")) p.axis = to_vec3(*v, "axis");
    if (const auto* v = spec.get("origin")) p.origin = to_vec3(*v, "origin");
  }
  field.width = int(p.a.size());
  field.values = evaluate_pattern(g.positions, p);
  return field;
}

//! --round-trip: the source carried forward to the last frame and back, compared with itself (§4.6); no files.
void run_round_trip(const std::vector<TrackedFrame>& frames, std::size_t source, const IdField& start) {
  const RoundTripReport r =
      round_trip(frames.size(), source, start, [&](std::size_t k) { return load_frame_events(frames, k); });
  const double range = r.range > 0 ? r.range : 1.0;
  std::printf("round trip frame %ld -> %ld -> %ld: %zu values (width %d), range %.6g; |error| max %.6g (%.3f%% of the "
              "range), mean %.6g (%.4f%%), rms %.6g (%.4f%%); %zu ids lost; %.3f s forward, %.3f s backward\n",
              frames[source].number, frames.back().number, frames[source].number, r.values, start.width, r.range,
              r.max_abs, 100 * r.max_abs / range, r.mean_abs, 100 * r.mean_abs / range, r.rms, 100 * r.rms / range,
              r.missing, r.forward_seconds, r.backward_seconds);
}

void run_propagate(const PropagateOptions& opt) {
  const auto t_start = std::chrono::steady_clock::now();
  if (opt.round_trip && (!opt.out.empty() || opt.in_place || !opt.morph_source.empty() || opt.displace != 0 ||
                         opt.direction != "forward"))
    TT_THROW(UsageError, "--round-trip writes nothing: no -o, --in-place, --morph-source, --displace or --direction");
  if (!opt.round_trip && opt.out.empty() == !opt.in_place)
    TT_THROW(UsageError, "give exactly one of -o OUT and --in-place");
  if (opt.direction != "forward" && opt.direction != "backward" && opt.direction != "both")
    TT_THROW(UsageError, "--direction must be forward, backward or both");
  const std::vector<TrackedFrame> frames = resolve_tracked_frames(opt.inputs);
  const std::size_t count = frames.size();
  const bool morph = !opt.morph_source.empty();
  if (morph && opt.direction != "forward") TT_THROW(UsageError, "--morph-source needs --direction forward");

  std::size_t source = opt.direction == "backward" ? count - 1 : 0;
  if (opt.from >= 0) {
    source = count;
    for (std::size_t k = 0; k < count; ++k)
      if (frames[k].number == opt.from) source = k;
    if (source == count) TT_THROW(UsageError, "--from " << opt.from << ": no frame with that number");
  }
  const SourceSpec spec = parse_spec(opt.source);
  const FrameFile src = read_frame_file(frames[source].mesh, true);
  const IdField start = evaluate_source(spec, src.data, src.geometry, frames[source].mesh);
  if (opt.round_trip) {
    run_round_trip(frames, source, start);
    return;
  }
  const fs::path out_dir = opt.in_place ? fs::path() : fs::path(opt.out);
  if (!opt.in_place) ensure_directory(out_dir);
  const int width = start.width;
  if (opt.displace != 0 && width != 1) TT_THROW(UsageError, "--displace needs a field of width 1, the source has " << width);
  const std::string name = !opt.name.empty() ? opt.name : width == 3 || width == 4 ? "color" : "value";
  std::vector<float> fallback = {0.5f};
  if (!opt.fallback.empty()) fallback = to_floats(opt.fallback, "--fallback");

  // Morph (§5): the second source on the last frame, propagated backward to every frame and kept in memory.
  std::vector<std::vector<float>> morph_values;
  if (morph) {
    const FrameFile last = read_frame_file(frames[count - 1].mesh, true);
    const IdField end = evaluate_source(parse_spec(opt.morph_source), last.data, last.geometry, frames[count - 1].mesh);
    if (end.width != width) TT_THROW(UsageError, "--morph-source has width " << end.width << ", the source " << width);
    morph_values.resize(count);
    propagate_sequence(
        count, count - 1, false, end, [&](std::size_t k) { return load_frame_events(frames, k); },
        [&](std::size_t k, const IdTable& table) {
          gather_values(table, read_frame_file(frames[k].mesh, true).geometry.ids, fallback, morph_values[k]);
        });
  }

  std::size_t missing = 0, written = 0;
  SequencePropagateReport total;
  auto emit = [&](std::size_t k, const IdTable& table) {
    FrameFile f = read_frame_file(frames[k].mesh, true);
    std::vector<float> values;
    missing += gather_values(table, f.geometry.ids, fallback, values);
    if (morph) {
      const double t = count > 1 ? double(k) / double(count - 1) : 0.0;
      values = blend_fields(values, morph_values[k], t);
    }
    if (opt.displace != 0) {
      const std::vector<double> h(values.begin(), values.end());
      const std::vector<Vec3> moved = displace_along_normals(f.geometry.positions, f.geometry.triangles, h, opt.displace);
      set_positions(f.data, moved);
    }
    set_attribute(f.data, name, width, std::move(values));
    const fs::path target = opt.in_place ? frames[k].mesh : out_dir / frames[k].mesh.filename().replace_extension(".ply");
    write_ply(target, f.data);
    if (!opt.in_place && k > 0 && fs::exists(frames[k].events))
      fs::copy_file(frames[k].events, out_dir / frames[k].events.filename(), fs::copy_options::overwrite_existing);
    ++written;
    if (!opt.quiet) std::fprintf(stderr, "\rpropagate: %zu/%zu frames", written, count);
  };
  auto events_of = [&](std::size_t k) { return load_frame_events(frames, k); };
  SequencePropagateReport rep;
  if (opt.direction != "backward") {
    propagate_sequence(count, source, true, start, events_of, emit, &rep);
    total.events += rep.events;
    total.propagate_seconds += rep.propagate_seconds;
  }
  if (opt.direction != "forward") {
    bool skip_source = opt.direction == "both";
    propagate_sequence(
        count, source, false, start, events_of,
        [&](std::size_t k, const IdTable& table) {
          if (skip_source && k == source) return;
          emit(k, table);
        },
        &rep);
    total.events += rep.events;
    total.propagate_seconds += rep.propagate_seconds;
  }
  if (!opt.quiet) std::fprintf(stderr, "\n");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  std::printf("propagated '%s' (width %d) from frame %ld %s over %zu frames, %zu events: %.3f s in the rules, %.3f s "
              "total; %zu vertex values missing (set to the fallback)\n",
              name.c_str(), width, frames[source].number, opt.direction.c_str(), written, total.events,
              total.propagate_seconds, seconds, missing);
}

void add_propagate_command(CLI::App& app) {
  auto opt = std::make_shared<PropagateOptions>();
  CLI::App* sub = app.add_subcommand(
      "propagate", "Carry a per-vertex attribute through a tracked sequence's event lists (§4.6): colours, "
                   "displacements, any float array; forward or backward from a frame");
  sub->add_option("FRAMES", opt->inputs, "tracked frames (folder, glob or pattern of `topotrack track` output)")
      ->required();
  sub->add_option("-o,--output", opt->out, "output folder (frames written with the attribute, events copied)");
  sub->add_flag("--in-place", opt->in_place, "rewrite the input PLYs instead (atomically)");
  sub->add_option("--from", opt->from, "frame number where the source is applied (default: first, or last backward)");
  sub->add_option("--direction", opt->direction, "forward, backward or both")->capture_default_str();
  sub->add_option("--source", opt->source,
                  "checker|stripes|sine[:cell=S,axis=x|y|z|a/b/c,origin=..,a=r/g/b,b=r/g/b], constant:value=v/..,"
                  " attribute:name=NAME, image:file=F.png[,azimuth=A,elevation=E,up=y]")
      ->capture_default_str();
  sub->add_option("--morph-source", opt->morph_source,
                  "morph (§5): this source on the last frame is propagated backward and blended with the forward one");
  sub->add_option("--name", opt->name, "output attribute name (default color for width 3/4, else value)");
  sub->add_option("--fallback", opt->fallback, "value for vertices no rule reaches, v or v/v/v (default 0.5)");
  sub->add_option("--displace", opt->displace,
                  "displacement map (§5): move each vertex along its normal by SCALE times the (scalar) value");
  sub->add_flag("--round-trip", opt->round_trip,
                "carry the source forward to the last frame and back, print the error against itself (§4.6)");
  sub->add_flag("-q,--quiet", opt->quiet, "no progress line");
  sub->callback([opt] { run_propagate(*opt); });
}

}  // namespace

TOPOTRACK_COMMAND(90, add_propagate_command);

}  // namespace topotrack::cli
