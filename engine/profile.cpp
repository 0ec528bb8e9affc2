#include "engine/profile.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <variant>

#include "io/error.hpp"
#include "io/mapped_file.hpp"

namespace topotrack {
namespace {

//! One parameter: its dotted name and where it lives. The single table that loading, overriding and
//! dumping all go through, so a parameter is declared once.
struct Binding {
  std::string name;
  std::variant<double*, int*, bool*> target;
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
};

std::vector<Binding> bindings(TrackerParams& p) {
  const double inf = std::numeric_limits<double>::infinity();
  return {
      {"tracker.edge_length", &p.edge_length, -inf, inf},
      {"tracker.voxel_size_factor", &p.voxel_size_factor, 1e-3, 1e3},
      {"tracker.voxel_size", &p.voxel_size, 0, inf},
      {"tracker.extraction_grid", &p.extraction_grid},
      {"tracker.sdf_half_width", &p.sdf_half_width, 1.75, 64},  // below √3 cells lose corner values
      {"tracker.topology_tolerance", &p.topology_tolerance, 0, 2},
      {"tracker.small_component_voxels", &p.small_component_voxels, 0, 1e6},
      {"tracker.topology_refinements", &p.topology_refinements, 0, 3},
      {"tracker.exact_sign_band", &p.exact_sign_band, 0, 3},
      {"tracker.coarse", &p.coarse},
      {"tracker.fine", &p.fine},
      {"tracker.topology", &p.topology},
      {"tracker.projection_only", &p.projection_only},
      {"improve.ratio", &p.improve.ratio, 1.01, 1e3},
      {"improve.min_angle_deg", &p.improve.min_angle_deg, 0, 59},
      {"improve.min_dihedral_deg", &p.improve.min_dihedral_deg, 0, 179},
      {"improve.max_iterations", &p.improve.max_iterations, 0, 1e6},
      {"improve.enable_flips", &p.improve.enable_flips},
      {"improve.max_surface_deviation", &p.improve.max_surface_deviation, 0, inf},
      {"improve.max_operation_deviation", &p.improve.max_operation_deviation, 0, inf},
      {"improve.max_flip_bend_deg", &p.improve.max_flip_bend_deg, 0, 180},
      {"improve.crease_collapse_fraction", &p.improve.crease_collapse_fraction, 0, 1},
      {"coarse.node_spacing_factor", &p.coarse_params.node_spacing_factor, 1e-3, 1e3},
      {"coarse.k", &p.coarse_params.k, 1, 16},
      {"coarse.alpha_point", &p.coarse_params.alpha_point, 0, inf},
      {"coarse.alpha_plane", &p.coarse_params.alpha_plane, 0, inf},
      {"coarse.alpha_fit", &p.coarse_params.alpha_fit, 0, inf},
      {"coarse.alpha_reg_start", &p.coarse_params.alpha_reg_start, 0, inf},
      {"coarse.alpha_reg_min", &p.coarse_params.alpha_reg_min, 0, inf},
      {"coarse.max_normal_angle_deg", &p.coarse_params.max_normal_angle_deg, 0, 180},
      {"coarse.max_closest_ratio", &p.coarse_params.max_closest_ratio, 1, inf},
      {"coarse.smooth_weight", &p.coarse_params.smooth_weight, 0, inf},
      {"coarse.max_iterations", &p.coarse_params.max_iterations, 1, 1e6},
      {"coarse.max_iterations_per_level", &p.coarse_params.max_iterations_per_level, 1, 1e6},
      {"coarse.convergence_tolerance", &p.coarse_params.convergence_tolerance, 0, 1},
      {"coarse.step_tolerance", &p.coarse_params.step_tolerance, 0, inf},
      {"coarse.stall_ratio", &p.coarse_params.stall_ratio, 0, 1},
      {"coarse.fit_tolerance", &p.coarse_params.fit_tolerance, 0, inf},
      {"coarse.check_fit_first_tolerance", &p.coarse_params.check_fit_first_tolerance, 0, inf},
      {"coarse.pcg_tolerance", &p.coarse_params.pcg_tolerance, 0, 1},
      {"coarse.max_pcg_iterations", &p.coarse_params.max_pcg_iterations, 1, 1e6},
      {"coarse.graph_density", &p.coarse_params.graph_density, 1e-3, 1e3},
      // Large motion (our additions before §4.2's scheme, gated by the misfit; kernels/registration/coarse.hpp).
      {"coarse.prealign_misfit", &p.coarse_params.prealign_misfit, 0, 1},
      {"coarse.prealign_axes_win_ratio", &p.coarse_params.prealign.axes_win_ratio, 0, 1},
      {"coarse.coarse_pass_misfit", &p.coarse_params.coarse_pass_misfit, 0, 1},
      {"coarse.coarse_pass_density", &p.coarse_params.coarse_pass_density, 1e-3, 1},
      {"coarse.coarse_pass_alpha_reg_min", &p.coarse_params.coarse_pass_alpha_reg_min, 1e-12, inf},
      {"coarse.near_pass_density", &p.coarse_params.near_pass_density, 0, 1},
      {"coarse.near_pass_misfit", &p.coarse_params.near_pass_misfit, 0, 1},
      {"coarse.near_pass_min_spacing", &p.coarse_params.near_pass_min_spacing, 0, 1},
      {"coarse.near_pass_max_iterations_per_level", &p.coarse_params.near_pass_max_iterations_per_level, 1, 1e6},
      {"coarse.max_iterations_per_level_after_pass", &p.coarse_params.max_iterations_per_level_after_pass, 1, 1e6},
      {"coarse.alpha_reg_start_after_pass", &p.coarse_params.alpha_reg_start_after_pass, 0, inf},
      {"coarse.alpha_reg_start_without_pass", &p.coarse_params.alpha_reg_start_without_pass, 0, inf},
      {"coarse.closest_point_levels", &p.coarse_params.closest_point_levels, 0, 16},
      {"coarse.backward_weight", &p.coarse_params.backward_weight, 0, inf},
      {"coarse.backward_misfit", &p.coarse_params.backward_misfit, 0, 1},
      {"coarse.backward_all_misfit", &p.coarse_params.backward_all_misfit, 0, inf},
      {"coarse.backward_samples_per_node", &p.coarse_params.backward_samples_per_node, 1, 1e6},
      {"coarse.intrinsic_full_graph", &p.coarse_params.intrinsic_full_graph},
      {"coarse.intrinsic_passes", &p.coarse_params.intrinsic_passes, 0, 16},
      {"coarse.intrinsic_pass_max_iterations_per_level", &p.coarse_params.intrinsic_pass_max_iterations_per_level, 1, 1e6},
      {"coarse.intrinsic_anchors", &p.coarse_params.intrinsic.anchors, 2, 1024},
      {"coarse.intrinsic_tolerance", &p.coarse_params.intrinsic.tolerance, 0, 1},
      {"coarse.intrinsic_misplaced_spacings", &p.coarse_params.intrinsic.misplaced_spacings, 0, 1e6},
      {"coarse.dense_spacing_factor", &p.coarse_params.dense_spacing_factor, 0, 1e3},
      {"coarse.dense_alpha_reg", &p.coarse_params.dense_alpha_reg, 1e-12, inf},
      {"coarse.dense_max_pcg_iterations", &p.coarse_params.dense_max_pcg_iterations, 1, 1e6},
      {"coarse.min_nodes", &p.coarse_params.min_nodes, 0, 1e7},
      {"coarse.min_node_spacing_factor", &p.coarse_params.min_node_spacing_factor, 1e-3, 1e3},
      {"coarse.vertex_fit_weight", &p.coarse_params.vertex_fit_weight, 0, inf},
      {"coarse.backward_vertex_weight", &p.coarse_params.backward_vertex_weight, 0, inf},
      {"coarse.vertex_fit_spacing", &p.coarse_params.vertex_fit_spacing, 0, 1e3},
      {"coarse.vertex_fit_max_disagreement", &p.coarse_params.vertex_fit_max_disagreement, 0, inf},
      // Speed between consecutive frames (our additions, kernels/registration/coarse.hpp).
      {"coarse.retract_rotations", &p.coarse_params.retract_rotations},
      {"coarse.check_fit_first", &p.coarse_params.check_fit_first},
      {"fine.sigma", &p.fine_params.sigma, 0, inf},
      {"fine.max_normal_angle_deg", &p.fine_params.max_normal_angle_deg, 0, 180},
      {"fine.fit_weight", &p.fine_params.fit_weight, 0, inf},
      {"fine.smooth_weight", &p.fine_params.smooth_weight, 0, inf},
      {"fine.max_cg_iterations", &p.fine_params.max_cg_iterations, 1, 1e7},
      {"fine.tolerance", &p.fine_params.tolerance, 0, 1},
      {"fine.rounds", &p.fine_params.rounds, 1, 100},
      {"fine.max_rounds", &p.fine_params.max_rounds, 1, 100},
      {"fine.more_rounds_residual", &p.fine_params.more_rounds_residual, 0, 1},
      {"fine.more_rounds_tolerance", &p.fine_params.more_rounds_tolerance, 0, 1},
      {"fine.normal_displacement", &p.fine_params.normal_displacement},
      {"fine.relax_iterations", &p.fine_params.relax.iterations, 0, 1e6},
      {"fine.relax_plane_weight", &p.fine_params.relax.plane_weight, 1e-9, 1e12},
      {"fine.relax_point_weight", &p.fine_params.relax.point_weight, 1e-12, 1e12},
      {"fine.relax_cg_iterations", &p.fine_params.relax.cg_iterations, 1, 1e6},
      {"topology.max_region_growth", &p.constrain.max_region_growth, 0, 64},
  };
}

Binding* find(std::vector<Binding>& table, const std::string& name) {
  for (auto& b : table)
    if (b.name == name) return &b;
  return nullptr;
}

std::string known_names(std::vector<Binding>& table) {
  std::string s;
  for (const auto& b : table) s += (s.empty() ? "" : ", ") + b.name;
  return s;
}

//! Set one parameter from JSON; `origin` names where the value came from for error messages.
void set_value(Binding& b, const nlohmann::json& v, const std::string& origin) {
  std::visit(
      [&](auto* ptr) {
        using T = std::remove_pointer_t<decltype(ptr)>;
        if constexpr (std::is_same_v<T, bool>) {
          if (!v.is_boolean()) TT_THROW(InvalidInput, origin << ": " << b.name << " must be true or false");
          *ptr = v.get<bool>();
        } else {
          if (!v.is_number()) TT_THROW(InvalidInput, origin << ": " << b.name << " must be a number");
          const double d = v.get<double>();
          if (!std::isfinite(d) || d < b.min || d > b.max)
            TT_THROW(InvalidInput, origin << ": " << b.name << " = " << d << " is outside [" << b.min << ", " << b.max
                                          << "]");
          if constexpr (std::is_same_v<T, int>) {
            if (d != std::floor(d)) TT_THROW(InvalidInput, origin << ": " << b.name << " must be an integer");
            *ptr = int(d);
          } else {
            *ptr = d;
          }
        }
      },
      b.target);
}

nlohmann::json read_json_file(const std::filesystem::path& path) {
  const MappedFile file(path);
  try {
    return nlohmann::json::parse(file.text());
  } catch (const nlohmann::json::parse_error& e) {
    TT_THROW(InvalidInput, path.string() << ": not valid JSON: " << e.what());
  }
}

std::filesystem::path resolve_profile(const std::string& name_or_path) {
  namespace fs = std::filesystem;
  if (name_or_path.find('/') != std::string::npos || fs::path(name_or_path).extension() == ".json") {
    if (!fs::exists(name_or_path)) TT_THROW(UsageError, "profile file '" << name_or_path << "' does not exist");
    return name_or_path;
  }
  const fs::path p = profiles_directory() / (name_or_path + ".json");
  if (!fs::exists(p)) {
    std::string names;
    for (const auto& n : profile_names()) names += (names.empty() ? "" : ", ") + n;
    TT_THROW(UsageError, "unknown profile '" << name_or_path << "' (bundled: " << names << ")");
  }
  return p;
}

void apply_profile_depth(TrackerParams& params, const nlohmann::json& profile, const std::string& origin,
                         int depth) {
  if (!profile.is_object()) TT_THROW(InvalidInput, origin << ": a profile must be a JSON object");
  if (depth > 8) TT_THROW(InvalidInput, origin << ": profile 'base' chain too deep (a cycle?)");
  if (auto it = profile.find("base"); it != profile.end()) {
    if (!it->is_string()) TT_THROW(InvalidInput, origin << ": 'base' must be a profile name");
    const auto path = resolve_profile(it->get<std::string>());
    apply_profile_depth(params, read_json_file(path), path.string(), depth + 1);
  }
  auto table = bindings(params);
  for (const auto& [key, value] : profile.items()) {
    if (key == "base" || key == "description") continue;
    if (value.is_object()) {
      for (const auto& [sub, v] : value.items()) {
        Binding* b = find(table, key + "." + sub);
        if (!b) TT_THROW(InvalidInput, origin << ": unknown parameter '" << key << "." << sub << "' (known: "
                                              << known_names(table) << ")");
        set_value(*b, v, origin);
      }
    } else {
      Binding* b = find(table, key);
      if (!b) TT_THROW(InvalidInput, origin << ": unknown parameter '" << key << "'");
      set_value(*b, value, origin);
    }
  }
}

}  // namespace

std::filesystem::path profiles_directory() {
  namespace fs = std::filesystem;
  if (const char* env = std::getenv("TOPOTRACK_PROFILES"); env && *env) return env;
#ifdef TOPOTRACK_SOURCE_PROFILES
  if (fs::is_directory(TOPOTRACK_SOURCE_PROFILES)) return TOPOTRACK_SOURCE_PROFILES;
#endif
#ifdef TOPOTRACK_INSTALLED_PROFILES
  return TOPOTRACK_INSTALLED_PROFILES;
#else
  return "profiles";
#endif
}

std::vector<std::string> profile_names() {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(profiles_directory(), ec))
    if (e.path().extension() == ".json") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

void apply_profile(TrackerParams& params, const nlohmann::json& profile, const std::string& origin) {
  apply_profile_depth(params, profile, origin, 0);
}

TrackerParams load_profile(const std::string& name_or_path) {
  TrackerParams p;
  const auto path = resolve_profile(name_or_path);
  apply_profile(p, read_json_file(path), path.string());
  validate(p);
  return p;
}

void apply_setting(TrackerParams& params, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    TT_THROW(UsageError, "--set '" << assignment << "': expected name=value, e.g. coarse.alpha_reg_start=100");
  std::string name = assignment.substr(0, eq);
  const std::string text = assignment.substr(eq + 1);
  auto table = bindings(params);
  Binding* b = find(table, name);
  if (!b) b = find(table, "tracker." + name);
  if (!b) TT_THROW(UsageError, "--set: unknown parameter '" << name << "' (known: " << known_names(table) << ")");
  nlohmann::json value;
  if (text == "true" || text == "false") value = (text == "true");
  else {
    char* end = nullptr;
    const double d = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size())
      TT_THROW(UsageError, "--set " << name << ": '" << text << "' is not a number");
    value = d;
  }
  try {
    set_value(*b, value, "--set");
  } catch (const InvalidInput& e) {
    throw UsageError(e.what());
  }
}

nlohmann::json to_json(const TrackerParams& params) {
  TrackerParams copy = params;  // bindings() hands out mutable pointers; read them from a copy
  nlohmann::json out = nlohmann::json::object();
  for (const auto& b : bindings(copy)) {
    const auto dot = b.name.find('.');
    auto& section = out[b.name.substr(0, dot)];
    std::visit([&](auto* ptr) { section[b.name.substr(dot + 1)] = *ptr; }, b.target);
  }
  return out;
}

void validate(const TrackerParams& params) {
  if (params.improve.min_angle_deg * 3 >= 180)
    TT_THROW(InvalidInput, "improve.min_angle_deg must be below 60 (no triangle could satisfy it)");
}

}  // namespace topotrack
