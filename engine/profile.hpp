#pragma once
//! Tracker parameters (Algorithm 1 and the stages it calls) and their JSON profiles (profiles/*.json).
//! Every parameter has a dotted name ("coarse.alpha_reg_start"); a profile sets any subset of them, the
//! command line overrides single ones with "name=value", and the parameters in effect are written next
//! to the output. Defaults are the paper's values.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "kernels/improve/improve.hpp"
#include "kernels/registration/coarse.hpp"
#include "kernels/registration/fine.hpp"
#include "kernels/topology/constrain.hpp"

namespace topotrack {

struct TrackerParams {
  //! Target edge length L of the tracked mesh (§4.1); <= 0: the mean edge length of the first input frame.
  double edge_length = 0;
  //! Voxel size of the signed distance grids of §4.3 as a multiple of L.
  double voxel_size_factor = 1.0;
  //! > 0: the voxel size of the first lattice in world units, instead of voxel_size_factor × L. For surfaces
  //! that were extracted from a grid (marching cubes of a simulation's level set; `topotrack gen resurface`
  //! writes its voxel size to gen.json), that grid's spacing or half of it, with the grid's nodes at integer
  //! multiples of it (OpenVDB's convention without a translation): the lattice's nodes then sample the
  //! extraction's own sign pattern and see every tunnel and bridge the input has, however thin (resurfaced
  //! pcow, docs/results.md, 2026-11-25 late).
  double voxel_size = 0;
  //! With voxel_size 0: when the first frame's vertices lie on the edges of one grid (extraction_grid,
  //! kernels/sdf/extraction_grid.hpp; at any origin), the first lattice is that grid (through its origin, as
  //! every finer one: Tracker::lattice_origin) at half its spacing, or at its spacing
  //! where half would be finer than a quarter of voxel_size_factor × L (extraction_grid_voxel); otherwise
  //! (no grid, or one finer than that: a fine extraction tracked at a larger edge_length), with a warning in
  //! the first frame's report, voxel_size_factor × L as without it. On that grid a frame whose
  //! topology differs from the input's after lines 8-12 has them redone once on the same lattice with line
  //! 11's sign flips keeping φ_S's topology (before any of topology_refinements; engine/tracker.cpp).
  bool extraction_grid = false;
  //! ConstrainTopology(M, φ_S) tolerance, in voxels: at lattice nodes within this distance of both M and
  //! S, φ_S takes M's sign (see agree_near_surface in tracker.cpp), so alignment error below it causes no
  //! resampling. 0 is the paper's exact rule; then every node that M and S put on different sides makes
  //! its cells complex.
  double topology_tolerance = 0.5;
  //! Components of S_n and M whose bounding-box diagonal is at most this many voxels are matched after
  //! ConstrainTopology(M, φ_S) (engine/small_components.hpp): one of S that M does not come within half a
  //! voxel of is copied into M, one of M that S does not come within half a voxel of is removed. The lattice
  //! cannot see a droplet thinner than a voxel, so without this M loses it. 0 is the paper's rule (nothing
  //! matched).
  double small_component_voxels = 8;
  //! When M's number of components or Euler characteristic differs from S_n's after lines 8-12, give that
  //! result S_n's topology once more on a lattice of half the voxel size (φ_S taking φ_M's sign wherever the
  //! two surfaces pass within one voxel of the first lattice and the flip keeps φ_S's topology, then lines
  //! 11-12), up to this many times (voxel size / 2, / 4, ...), each from the first result. A finer result is
  //! kept only when its topology is S_n's and it has no more folds (dihedral below 45°) or triangles below
  //! 2° than the first; otherwise the first stays. The lattice cannot see a tunnel or a bridge thinner than
  //! a voxel; refining everywhere costs 8x the cells per halving on every frame, this only on the frames
  //! that need it. 0 is the paper's rule (one lattice).
  int topology_refinements = 0;
  //! Lattice nodes closer than this (in voxels) to the surface get the exact sign of the mesh (OpenVDB's
  //! can be wrong at concave creases, which made ConstrainTopology(M, φ_M) resample clean regions).
  double exact_sign_band = 0.25;
  //! Narrow-band half width of the signed distance grids, in voxels (the paper gives none). Beyond the band
  //! only the sign is kept. ConstrainTopology needs values at the corners of the cells the surface crosses,
  //! at most √3 ≈ 1.732 voxels (a cell's diagonal) from it; everything else it reads (marching-cubes
  //! crossings, the sign tolerance, agree_near_surface) lies within 1 voxel. 1.75 is the smallest round
  //! band above √3: output bit-identical to 2 and 3 (ConstrainSameBeyondCellDiagonal in
  //! tests/kernels/topology/constrain_test.cpp; blobs and resurfaced samba tracked with both), and ~15 %
  //! less signed-distance time than 2.
  double sdf_half_width = 1.75;

  // Stages of Algorithm 1 that can be switched off for the ablations of §6 (Fig. 8 and 9).
  bool coarse = true;            //!< line 5
  bool fine = true;              //!< line 6
  bool topology = true;          //!< lines 8-11
  bool projection_only = false;  //!< replace lines 5-6 by projection onto the closest point (Fig. 9)

  ImproveParams improve;
  CoarseParams coarse_params;
  FineParams fine_params;
  ConstrainParams constrain;
};

//! The voxel size of the first lattice (TrackerParams::voxel_size, else voxel_size_factor × edge_length).
inline double first_voxel_size(const TrackerParams& p, double edge_length) {
  return p.voxel_size > 0 ? p.voxel_size : p.voxel_size_factor * edge_length;
}

//! The first lattice's voxel size on an extraction grid of spacing r found in the first frame
//! (TrackerParams::extraction_grid): r/2, where a marching-cubes vertex at the middle of a grid edge is a node,
//! else r, the first of the two that is at least a quarter of `profile_voxel` (first_voxel_size; the finest
//! lattice two topology refinements reach); nothing when both are finer: a lattice 16 times as fine in each
//! direction as the one the profile asks for would cost far more than it, in time and memory.
inline std::optional<double> extraction_grid_voxel(double r, double profile_voxel) {
  for (const double h : {0.5 * r, r})
    if (h >= 0.25 * profile_voxel) return h;
  return std::nullopt;
}

//! The folder of the bundled profiles: $TOPOTRACK_PROFILES, else <source>/profiles, else the installed
//! share/topotrack/profiles.
std::filesystem::path profiles_directory();
//! Names of the bundled profiles (file stems), sorted.
std::vector<std::string> profile_names();

//! Apply a profile: a JSON object whose keys are section names ("improve", "coarse", ...) holding
//! parameter names, or dotted names at the top level. A "base" key names a profile applied first.
//! \throw InvalidInput naming `origin` on an unknown parameter, a wrong type or an out-of-range value.
void apply_profile(TrackerParams& params, const nlohmann::json& profile, const std::string& origin);
//! Load `name_or_path` (a bundled profile name, or a .json file) on top of the defaults.
//! \throw UsageError for an unknown name, IoError/InvalidInput for a bad file.
TrackerParams load_profile(const std::string& name_or_path);
//! Apply one "dotted.name=value" override. \throw UsageError naming the setting.
void apply_setting(TrackerParams& params, const std::string& assignment);
//! Every parameter, by section, as JSON (what `track` writes next to its output).
nlohmann::json to_json(const TrackerParams& params);
//! Check ranges across parameters. \throw InvalidInput naming the parameter.
void validate(const TrackerParams& params);

}  // namespace topotrack
