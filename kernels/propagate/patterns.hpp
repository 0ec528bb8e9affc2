#pragma once
//! Procedural sources of per-vertex data to propagate (§4.6, §5 colour and displacement maps): patterns in
//! space (3D checkerboard, stripes, a sine wave, a constant), and the blend of two fields (§5 morph).
//! An image projected onto a frame is the other source: kernels/propagate/image_projection.hpp.
#include <span>
#include <string>
#include <vector>

#include "kernels/mesh/mesh_queries.hpp"

namespace topotrack {

enum class PatternKind { Checker, Stripes, Sine, Constant };

struct PatternParams {
  PatternKind kind = PatternKind::Checker;
  double cell = 0;              //!< checker cell, stripe width, half the sine period; <= 0: 1/8 of the bbox diagonal
  Vec3 axis = Vec3::UnitX();    //!< stripes and sine run along this direction
  Vec3 origin = Vec3::Zero();   //!< where the pattern is anchored
  std::vector<float> a = {0.95f, 0.95f, 0.92f};  //!< first value (its size is the width of the result)
  std::vector<float> b = {0.12f, 0.25f, 0.65f};  //!< second value, same size
};

//! The pattern at each position, a.size() floats per vertex: checker = a or b by the parity of
//! floor(x/cell)+floor(y/cell)+floor(z/cell); stripes = a or b by the parity of floor(<p-origin,axis>/cell);
//! sine = a + (b - a) (1 + sin(pi <p-origin,axis> / cell)) / 2 (smooth); constant = a.
//! \throw InvalidInput on empty or differently sized a and b, a zero axis or non-finite positions.
std::vector<float> evaluate_pattern(std::span<const Vec3> positions, const PatternParams& params);

//! Parse "checker", "stripes", "sine", "constant". \throw InvalidInput otherwise.
PatternKind parse_pattern_kind(const std::string& name);

//! Linear blend (1 - t) a + t b of two fields of the same size (the morph of §5 blends forward- and
//! backward-propagated colours this way). \throw InvalidInput on different sizes.
std::vector<float> blend_fields(std::span<const float> a, std::span<const float> b, double t);

}  // namespace topotrack
