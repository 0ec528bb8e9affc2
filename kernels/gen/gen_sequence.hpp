#pragma once
//! Writing generated input sequences with ground truth to a folder (`topotrack gen`, issue 2 item 7):
//!   DIR/<kind>.%04d.ply        the frames, numbered from 1 (binary PLY)
//!   DIR/gen.json               what was generated: parameters, voxel size, per frame counts and topology
//!   DIR/ground_truth.json      blobs / morph / metaballs: SyntheticScene::ground_truth()
//!   DIR/ground_truth/          resurface: byte copies of the coherent source frames, numbered like the output
#include <array>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace topotrack {

struct GenFrameReport {
  int frame = 0;
  std::string file;         //!< output file name (relative to DIR)
  std::string source_file;  //!< resurface: the source frame
  std::size_t vertices = 0, triangles = 0;
  long components = 0, genus = 0;
  std::size_t voids_filled = 0;  //!< resurface: enclosed cavities filled (ResurfaceReport)
  double seconds = 0;
};

struct GenParams {
  std::string kind = "blobs";  //!< blobs, morph, metaballs, resurface
  int frames = 0;              //!< 0: 60 for synthetic kinds, every selected source frame for resurface
  //! Voxels across the largest side of the bounding box (resurface: of the first selected source frame);
  //! 0: the kind's default (synthetic: ~10k-20k vertices; resurface: 128).
  int resolution = 0;
  unsigned seed = 1;
  //! Synthetic kinds: write only frames 1..last_frame of the `frames`-frame sequence (0: all). The motion per
  //! frame depends on `frames` (blobs: one turn over the sequence), so this gives the first steps of a long
  //! sequence without generating the rest (the Table 1 harness tracks a few frames at high resolution).
  int last_frame = 0;
  std::string source;  //!< resurface: the coherent sequence (folder, glob or frame pattern)
  long start = -1;     //!< resurface: first source frame number used (-1: the first frame)
  int every = 1;       //!< resurface: use every n-th source frame
  //! resurface: the extraction grid's nodes at (grid_offset + (i, j, k)) × voxel size (a simulation domain's
  //! corner, cell-centred samples); each in [0, 1), 0: nodes at multiples of the voxel size.
  std::array<double, 3> grid_offset{0, 0, 0};
  //! Called after each frame with its report and the total frame count; may be empty.
  std::function<void(const GenFrameReport&, int)> progress;
};


struct GenReport {
  std::string kind;
  int resolution = 0;
  double voxel_size = 0;
  std::vector<GenFrameReport> frames;
  double seconds = 0;
};

//! Generate and write the sequence. Every frame is checked to be a closed 2-manifold before it is written.
//! \throw UsageError for an unknown kind or a missing source; InvalidInput for bad parameters or source
//! frames; IoError when DIR cannot be written.
GenReport generate_sequence(const GenParams& params, const std::filesystem::path& dir);

}  // namespace topotrack
