// topotrack eval OUT --input INPUT [--ground-truth GT]: per-frame quality of a tracked sequence against its
// input (distance, topology, closedness, triangle quality, resampling) and, with ground truth, the drift
// of tracked points. JSON (with where the Hausdorff distance is attained), a one-line summary, PNG plots
// and, with --per-vertex, a CSV per frame of each vertex's drift and distance (to find where they come from).
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <unordered_map>
#include <unordered_set>

#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "io/event_file.hpp"
#include "io/mapped_file.hpp"
#include "io/sequence.hpp"
#include "kernels/eval/drift.hpp"
#include "kernels/eval/plot.hpp"
#include "kernels/eval/surface_distance.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/mesh/soup_stats.hpp"
#include "kernels/propagate/propagate.hpp"
#include "kernels/render/png.hpp"
#include "tools/cli_common.hpp"
#include "tools/commands.hpp"

namespace topotrack::cli {
namespace {

std::string format(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}
namespace fs = std::filesystem;
using json = nlohmann::json;

struct EvalOptions {
  std::string out, input, ground_truth, json_out, plots, markdown, per_vertex;
  bool quiet = false;
};

//! Ground truth: rotations per frame number (the blobs generator) or coherent frames (resurfaced data).
struct GroundTruth {
  std::map<long, std::pair<Eigen::Matrix3d, Vec3>> rotations;  // frame -> (R, centre)
  std::map<long, fs::path> frames;
  bool empty() const { return rotations.empty() && frames.empty(); }
};

Eigen::Matrix3d matrix_from_json(const json& m, const std::string& where) {
  Eigen::Matrix3d R;
  if (!m.is_array() || m.size() != 3) TT_THROW(InvalidInput, where << ": rotation must be a 3x3 array");
  for (int r = 0; r < 3; ++r) {
    if (!m[r].is_array() || m[r].size() != 3) TT_THROW(InvalidInput, where << ": rotation must be a 3x3 array");
    for (int c = 0; c < 3; ++c) R(r, c) = m[r][c].get<double>();
  }
  return R;
}

Vec3 vec_from_json(const json& v, const std::string& where) {
  if (!v.is_array() || v.size() != 3) TT_THROW(InvalidInput, where << ": expected [x, y, z]");
  return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}

GroundTruth load_ground_truth(const std::string& spec) {
  GroundTruth gt;
  if (spec.empty()) return gt;
  if (fs::path(spec).extension() == ".json") {
    const MappedFile f(spec);
    json j;
    try {
      j = json::parse(f.text());
      for (const auto& fr : j.at("frames")) {
        const long n = fr.at("frame").get<long>();
        gt.rotations[n] = {matrix_from_json(fr.at("rotation"), spec), vec_from_json(fr.value("center", json::array({0, 0, 0})), spec)};
      }
    } catch (const json::exception& e) {
      TT_THROW(InvalidInput, spec << ": not a ground-truth rotation file: " << e.what());
    }
    return gt;
  }
  for (const auto& f : find_frames(spec).frames) gt.frames[f.number] = f.path;
  return gt;
}

SurfaceMesh read_surface(const fs::path& p) {
  try {
    return to_surface_mesh(load_mesh_data(p));
  } catch (const InvalidInput& e) {
    const std::string what = e.what();
    if (what.rfind(p.string(), 0) == 0) throw;
    TT_THROW(InvalidInput, p.string() << ": " << what);
  }
}

std::vector<Vec3> live_positions(const SurfaceMesh& m) {
  std::vector<Vec3> p;
  for (Index i = 0; i < m.vertices_size(); ++i)
    if (!m.is_deleted(Vertex(i))) p.push_back(m.position(Vertex(i)));
  return p;
}

std::vector<VertexId> live_ids(const SurfaceMesh& m) {
  std::vector<VertexId> ids;
  for (Index i = 0; i < m.vertices_size(); ++i)
    if (!m.is_deleted(Vertex(i))) ids.push_back(m.id(Vertex(i)));
  return ids;
}

void write_plot(const fs::path& dir, const std::string& name, std::vector<PlotSeries> series, PlotParams p) {
  for (std::size_t i = 0; i < series.size(); ++i) series[i].color = series_color(i);
  write_png(dir / name, line_plot(series, p));
}

//! --per-vertex: one CSV per frame, a row per live vertex of the output: its id, the frame it first
//! appeared in, position, drift and distance to the input surface (fractions of the input's diagonal;
//! drift nan where unknown). For finding where drift and distance come from.
void write_per_vertex(const fs::path& dir, long frame, const SurfaceMesh& tracked, const SurfaceMesh& input, double diag,
                      const std::unordered_map<VertexId, long>& born, const std::vector<double>& drift) {
  const auto pos = live_positions(tracked);
  const auto ids = live_ids(tracked);
  const auto hits = TargetSurface::from_mesh(input).closest_points(pos);
  std::string text = "id,born,x,y,z,drift,distance\n";
  char buf[256];
  for (std::size_t i = 0; i < ids.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%lld,%ld,%.7g,%.7g,%.7g,%.6g,%.6g\n", static_cast<long long>(ids[i]), born.at(ids[i]),
                  pos[i][0], pos[i][1], pos[i][2], i < drift.size() ? drift[i] : NAN, hits[i].distance / diag);
    text += buf;
  }
  write_file_atomic(dir / ("vertices." + std::to_string(frame) + ".csv"), text);
}

void run_eval(const EvalOptions& opt) {
  const FrameSequence out = find_frames(opt.out);
  std::map<long, fs::path> inputs;
  for (const auto& f : find_frames(opt.input).frames) inputs[f.number] = f.path;
  const GroundTruth gt = load_ground_truth(opt.ground_truth);

  json frames = json::array();
  IdTable material(3);  // frame-1 positions carried forward through the events (§4.6)
  std::unordered_set<VertexId> previous_ids;
  std::unordered_map<VertexId, long> born;  // id -> first frame it appears in (for --per-vertex)
  if (!opt.per_vertex.empty()) ensure_directory(opt.per_vertex);
  std::unique_ptr<TargetSurface> gt_first;
  Eigen::Matrix3d R_first = Eigen::Matrix3d::Identity();
  long first_number = -1;
  std::size_t topo_ok = 0, closed_ok = 0;
  double worst_mean = 0, worst_hausdorff = 0, sum_new_share = 0;
  json last_drift;
  std::vector<double> xs, dist_mean, dist_haus, drift_mean, new_share, removed_share;

  for (std::size_t k = 0; k < out.frames.size(); ++k) {
    const auto& of = out.frames[k];
    auto in_it = inputs.find(of.number);
    if (in_it == inputs.end()) TT_THROW(InvalidInput, opt.input << ": no input frame " << of.number << " for " << of.path.string());
    const SurfaceMesh tracked = read_surface(of.path);
    const SurfaceMesh input = read_surface(in_it->second);
    const double diag = bounding_box(input).diagonal();

    // Events taking the previous output frame to this one.
    fs::path ev_path = of.path;
    ev_path.replace_extension(".events");
    EventList events;
    if (k > 0 && fs::exists(ev_path)) events = read_events(ev_path);
    if (k == 0) {
      first_number = of.number;
      material = IdTable::from_field(position_field(tracked));
    } else {
      propagate_forward(events, material);
    }

    json fj;
    fj["frame"] = of.number;
    fj["vertices"] = tracked.n_vertices();
    fj["triangles"] = tracked.n_faces();
    const SurfaceDistance d = surface_distance(tracked, input);
    const bool from_output = d.a_to_b.max >= d.b_to_a.max;  // where the Hausdorff distance is attained
    const Vec3 h_at = from_output ? d.a_to_b.max_point : d.b_to_a.max_point;
    fj["distance"] = {{"mean", d.mean() / diag}, {"hausdorff", d.hausdorff() / diag}, {"unit", "fraction of bbox diagonal"},
                      {"hausdorff_at", {h_at[0], h_at[1], h_at[2]}},
                      {"hausdorff_from", from_output ? "output" : "input"}};
    worst_mean = std::max(worst_mean, d.mean() / diag);
    worst_hausdorff = std::max(worst_hausdorff, d.hausdorff() / diag);
    const SoupStats so = analyze_soup(to_mesh_data(tracked, false));
    const SoupStats si = analyze_soup(to_mesh_data(input, false));
    fj["components"] = {{"output", so.components}, {"input", si.components}};
    fj["euler"] = {{"output", so.euler}, {"input", si.euler}};
    const bool topo_match = so.components == si.components && so.euler == si.euler;
    fj["topology_matches"] = topo_match;
    fj["closed_manifold"] = so.closed_manifold();
    topo_ok += topo_match;
    closed_ok += so.closed_manifold();
    const QualityStats q = quality_stats(tracked);
    fj["quality"] = {{"min_angle_deg", q.min_angle_deg},
                     {"share_below_10deg", q.share_below_10deg},
                     {"below_2deg", q.below_2deg},
                     {"min_dihedral_deg", q.min_dihedral_deg},
                     {"dihedral_below_45deg", q.dihedral_below_45deg},
                     {"edge_length_ratio", q.edge_length.min > 0 ? q.edge_length.max / q.edge_length.min : INFINITY}};
    const auto ids = live_ids(tracked);
    std::size_t fresh = 0;
    std::unordered_set<VertexId> now(ids.begin(), ids.end());
    for (VertexId id : ids) fresh += k > 0 && !previous_ids.count(id);
    for (VertexId id : ids) born.emplace(id, of.number);
    std::size_t removed = 0;
    for (VertexId id : previous_ids) removed += !now.count(id);
    const double ns = ids.empty() ? 0 : double(fresh) / double(ids.size());
    fj["resampling"] = {{"new_vertices", fresh}, {"removed_vertices", removed}, {"new_share", ns}};
    const auto by_kind = events.count_by_kind();
    json ek = json::object();
    for (int kk = 1; kk <= kEventKindCount; ++kk) ek[std::string(to_string(EventKind(kk)))] = by_kind[kk - 1];
    fj["events"] = ek;
    if (k > 0) sum_new_share += ns;
    previous_ids = std::move(now);

    double drift = NAN;
    std::vector<double> per_vertex_drift;
    if (!gt.empty()) {
      std::vector<float> mat;
      const std::vector<float> none(3, NAN);
      gather_values(material, ids, none, mat);
      std::vector<Vec3> tracked_p, material_p;
      std::vector<std::size_t> row;  // per point with a material position: its index in ids
      const auto pos = live_positions(tracked);
      for (std::size_t i = 0; i < ids.size(); ++i) {
        if (!std::isfinite(mat[3 * i])) continue;
        tracked_p.push_back(pos[i]);
        material_p.push_back(Vec3(mat[3 * i], mat[3 * i + 1], mat[3 * i + 2]));
        row.push_back(i);
      }
      std::vector<Vec3> expected;
      bool have = false;
      if (!gt.rotations.empty()) {
        auto a = gt.rotations.find(first_number), b = gt.rotations.find(of.number);
        if (a != gt.rotations.end() && b != gt.rotations.end()) {
          if (k == 0) R_first = a->second.first;
          expected = expected_by_rotation(material_p, b->second.first * R_first.transpose(), b->second.second);
          have = true;
        }
      } else {
        auto a = gt.frames.find(first_number), b = gt.frames.find(of.number);
        if (a != gt.frames.end() && b != gt.frames.end()) {
          if (!gt_first) gt_first = std::make_unique<TargetSurface>(TargetSurface::from_mesh(read_surface(a->second)));
          expected = expected_by_correspondence(material_p, *gt_first, live_positions(read_surface(b->second)));
          have = true;
        }
      }
      if (have && !opt.per_vertex.empty()) {
        per_vertex_drift.assign(ids.size(), NAN);
        for (std::size_t j = 0; j < row.size(); ++j) per_vertex_drift[row[j]] = (tracked_p[j] - expected[j]).norm() / diag;
      }
      if (have) {
        const DriftStats ds = drift_stats(tracked_p, expected);
        fj["drift"] = {{"points", ds.points}, {"mean", ds.mean / diag}, {"median", ds.median / diag},
                       {"rms", ds.rms / diag}, {"max", ds.max / diag}, {"unit", "fraction of bbox diagonal"}};
        // The same over the vertices that date from the first frame (same id): the alignment's drift alone,
        // without what the §4.4 rules interpolate onto vertices created by resampling.
        std::vector<Vec3> kept_p, kept_expected;
        for (std::size_t j = 0; j < row.size(); ++j)
          if (born.at(ids[row[j]]) == first_number) {
            kept_p.push_back(tracked_p[j]);
            kept_expected.push_back(expected[j]);
          }
        const DriftStats dk = drift_stats(kept_p, kept_expected);
        fj["drift"]["first_frame_vertices"] = {{"points", dk.points}, {"mean", dk.mean / diag},
                                               {"median", dk.median / diag}, {"max", dk.max / diag}};
        last_drift = fj["drift"];
        drift = ds.mean / diag;
      }
    }
    if (!opt.per_vertex.empty()) write_per_vertex(opt.per_vertex, of.number, tracked, input, diag, born, per_vertex_drift);
    xs.push_back(double(of.number));
    dist_mean.push_back(100 * d.mean() / diag);
    dist_haus.push_back(100 * d.hausdorff() / diag);
    drift_mean.push_back(100 * drift);
    new_share.push_back(100 * ns);
    removed_share.push_back(ids.empty() ? 0 : 100.0 * double(removed) / double(ids.size()));
    frames.push_back(fj);
  }

  // The tracker's own record, when OUT was written by `topotrack track`: seconds per frame.
  json track;
  const fs::path track_json = fs::path(opt.out) / "track.json";
  if (fs::exists(track_json)) {
    const MappedFile f(track_json);
    track = json::parse(f.text(), nullptr, /*allow_exceptions=*/false);
    if (!track.is_object() || !track.contains("frames") || !track["frames"].is_array()) track = json();
  }
  std::vector<double> frame_seconds;
  if (!track.is_null())
    for (const auto& fr : track["frames"])
      if (fr.value("index", 0) > 0 && fr.contains("seconds")) frame_seconds.push_back(fr["seconds"].value("total", 0.0));

  const std::size_t n = out.frames.size();
  json summary = {{"frames", n},
                  {"worst_mean_distance", worst_mean},
                  {"worst_hausdorff", worst_hausdorff},
                  {"topology_matches", topo_ok},
                  {"closed_manifold", closed_ok},
                  {"mean_new_vertex_share", n > 1 ? sum_new_share / double(n - 1) : 0.0}};
  if (!last_drift.is_null()) summary["final_drift"] = last_drift;
  if (!frame_seconds.empty()) summary["median_seconds_per_frame"] = median(frame_seconds);
  const json result = {{"output", opt.out}, {"input", opt.input}, {"ground_truth", opt.ground_truth},
                       {"summary", summary}, {"frames", frames}};
  if (!opt.json_out.empty()) write_file_atomic(opt.json_out, result.dump(1) + "\n");

  if (!opt.plots.empty()) {
    ensure_directory(opt.plots);
    write_plot(opt.plots, "distance.png", {{"mean", xs, dist_mean}, {"hausdorff", xs, dist_haus}},
               {800, 420, "distance to input", "frame", "% of bbox diagonal"});
    write_plot(opt.plots, "resampling.png", {{"new", xs, new_share}, {"removed", xs, removed_share}},
               {800, 420, "resampling per frame", "frame", "% of vertices"});
    if (!last_drift.is_null())
      write_plot(opt.plots, "drift.png", {{"mean drift", xs, drift_mean}},
                 {800, 420, "drift against ground truth", "frame", "% of bbox diagonal"});
    if (!track.is_null()) {
      std::vector<PlotSeries> stages;
      for (const char* st : {"coarse", "fine", "improve", "signed_distance", "topology", "io"}) {
        PlotSeries ps{st, {}, {}};
        for (const auto& fr : track["frames"]) {
          ps.x.push_back(fr.value("frame", 0.0));
          ps.y.push_back(fr["seconds"].value(st, 0.0));
        }
        stages.push_back(ps);
      }
      write_plot(opt.plots, "seconds.png", stages, {800, 420, "seconds per stage", "frame", "seconds"});
    }
  }
  if (!opt.quiet) {
    std::printf("eval: %zu frames; distance mean <= %.4f%%, hausdorff <= %.3f%% of diagonal; topology %zu/%zu; "
                "closed manifold %zu/%zu; new vertices %.2f%%/frame",
                n, 100 * worst_mean, 100 * worst_hausdorff, topo_ok, n, closed_ok, n,
                100 * summary["mean_new_vertex_share"].get<double>());
    if (!last_drift.is_null())
      std::printf("; final drift mean %.4f%% (vertices from the first frame: %zu, %.4f%%)", 100 * last_drift["mean"].get<double>(),
                  last_drift["first_frame_vertices"]["points"].get<std::size_t>(),
                  100 * last_drift["first_frame_vertices"]["mean"].get<double>());
    std::printf("\n");
  }
  if (opt.json_out.empty() && opt.quiet) std::cout << result.dump(1) << "\n";
  if (!opt.markdown.empty()) {
    // A Markdown table (header and one row) for result tables such as docs/results.md; scripts that compare
    // several runs keep the header of the first.
    std::printf("| run | frames | mean distance | Hausdorff | topology = input | closed, non-degenerate | new vertices "
                "/frame | final drift (mean) | s/frame |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
    std::printf("| %s | %zu | %.4f%% | %.3f%% | %zu/%zu | %zu/%zu | %.2f%% | %s | %s |\n", opt.markdown.c_str(), n,
                100 * worst_mean, 100 * worst_hausdorff, topo_ok, n, closed_ok, n,
                100 * summary["mean_new_vertex_share"].get<double>(),
                last_drift.is_null() ? "n/a" : format("%.4f%%", 100 * last_drift["mean"].get<double>()).c_str(),
                frame_seconds.empty() ? "n/a" : format("%.2f", median(frame_seconds)).c_str());
  }
}

void add_eval_command(CLI::App& app) {
  auto opt = std::make_shared<EvalOptions>();
  CLI::App* sub = app.add_subcommand("eval", "Measure a tracked sequence against its input (and ground truth)");
  sub->add_option("OUT", opt->out, "folder of tracked frames (topotrack track output)")->required();
  sub->add_option("--input", opt->input, "the input sequence the frames were tracked from")->required();
  sub->add_option("--ground-truth", opt->ground_truth,
                  "ground_truth.json of `gen blobs`, or the coherent frames of `gen resurface`");
  sub->add_option("-o,--json", opt->json_out, "write the per-frame results as JSON");
  sub->add_option("--plots", opt->plots, "write PNG plots (distance, resampling, drift, seconds) into this folder");
  sub->add_option("--markdown", opt->markdown, "also print a Markdown table row for this run, labelled LABEL");
  sub->add_option("--per-vertex", opt->per_vertex,
                  "write a CSV per frame into this folder: id, first frame, position, drift, distance to the input");
  sub->add_flag("--quiet", opt->quiet, "no summary line (prints the JSON when -o is not given)");
  sub->callback([opt] { run_eval(*opt); });
}

}  // namespace

TOPOTRACK_COMMAND(50, add_eval_command);

}  // namespace topotrack::cli
