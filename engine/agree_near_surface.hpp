#pragma once
//! The tracker's topology tolerance (engine/tracker.cpp, between lines 10 and 11 of Algorithm 1).

#include <openvdb/openvdb.h>

namespace topotrack {

//! Where φ_S and φ_M disagree in sign at a lattice node that both surfaces pass within `tolerance` of,
//! take φ_M's value: M and S are then the same surface up to the alignment error there, and the sign
//! flip would only make ConstrainTopology(M, φ_S) resample an aligned region (the strict cell test of
//! §4.3 compares edge crossings exactly). Only flips that keep φ_S's topology are taken (the node is a
//! simple point of the inside/outside lattice sets): the flip moves S's surface by a node, never adds or
//! removes a component, a handle or a cavity, so every topology difference between M and S, however
//! small, stays one and ConstrainTopology(M, φ_S) gives M the input's topology (resurfaced samba: flips
//! that made a crumb of 4-16 vertices out of a thin part kept 4 of 40 frames from the input's number of
//! components). Candidates are found per leaf node in parallel and decided in 8 parity classes (nodes of a
//! class lie outside each other's 3×3×3 neighbourhoods), so the result is one fixed sequential order's.
//! `sweeps` passes over the candidates (0: until a pass flips nothing). Where S and M are several nodes
//! apart (a tolerance of several voxels, as on the tracker's finer lattices), a node between them becomes
//! simple only once the nodes nearer M's side have flipped, about one layer per pass. The tracker's first
//! lattice (half a voxel) keeps one pass: sweeping there too gave resurfaced pcow with the default profile
//! another trajectory, with a fold in one frame (docs/results.md).
void agree_near_surface(openvdb::FloatGrid& phi_s, const openvdb::FloatGrid& phi_m, double tolerance,
                        int sweeps = 0);

}  // namespace topotrack
