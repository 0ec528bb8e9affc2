#pragma once
//! Simple points of a lattice set (digital topology): a node whose sign can change without changing the
//! topology of the inside or of the outside. Used wherever a level set's signs are adjusted near its zero
//! set and the adjustment must not add or remove a component, a handle or a cavity: the tracker's
//! agreement of φ_S with φ_M (engine/agree_near_surface.hpp) and the signs index_cells takes from M's
//! crossings (classify.hpp, kSignTolerance).
#include <array>

namespace topotrack::topology {

//! The 3×3×3 neighbourhood of a lattice node, index (dx+1) + 3(dy+1) + 9(dz+1); 13 is the node itself;
//! true where the node is inside (value < 0).
using NodeBlock = std::array<bool, 27>;

//! Whether changing the sign of the centre leaves the topology of the inside (6-connected) and the outside
//! (18-connected) unchanged: the (6, 18) pair is the connectivity of the project's marching cubes, which
//! separates inside corners on an ambiguous face (kernels/sdf/cube_table.hpp). Bertrand and Malandain's
//! characterisation: one 6-component of the inside's geodesic neighbourhood and one 18-component of the
//! outside's.
bool simple_node(const NodeBlock& inside);

}  // namespace topotrack::topology
