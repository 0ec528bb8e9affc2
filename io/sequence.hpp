#pragma once
//! Frame-sequence discovery: a folder, a glob, or a frame pattern resolved to frames sorted by number.
#include <filesystem>
#include <string>
#include <vector>

namespace topotrack {

struct SequenceFrame {
  std::filesystem::path path;
  long number = -1;  //!< frame number parsed from the file name (the last run of digits before the extension)
};

struct FrameSequence {
  std::vector<SequenceFrame> frames;  //!< sorted by number (natural sort of names when numbers tie or are absent)
  std::vector<std::string> warnings;  //!< gaps in the numbering, mixed formats, ...
};

//! Resolve `spec` to frames. `spec` is one of:
//!  - a folder: every .obj/.ply/.vdb file in it (not recursive);
//!  - a glob with * and ? in the file-name part: "out/frame_*.ply";
//!  - a frame pattern: "name.####.ply" (# = one digit, padded), "name.%04d.obj" (printf), "name.$F4.ply"
//!    (Houdini), "name.{}.ply" (any number of digits).
//! \throw InvalidInput naming `spec` when nothing matches, when two files have the same frame number, or
//! when a folder does not exist.
FrameSequence find_frames(const std::string& spec);

}  // namespace topotrack
