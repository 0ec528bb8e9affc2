#include "kernels/propagate/patterns.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "io/error.hpp"

namespace topotrack {

PatternKind parse_pattern_kind(const std::string& name) {
  if (name == "checker") return PatternKind::Checker;
  if (name == "stripes") return PatternKind::Stripes;
  if (name == "sine") return PatternKind::Sine;
  if (name == "constant") return PatternKind::Constant;
  TT_THROW(InvalidInput, "unknown pattern '" << name << "' (checker, stripes, sine, constant)");
}

std::vector<float> evaluate_pattern(std::span<const Vec3> positions, const PatternParams& params) {
  const std::size_t w = params.a.size();
  if (w == 0 || params.b.size() != w)
    TT_THROW(InvalidInput, "pattern: values of sizes " << params.a.size() << " and " << params.b.size());
  if (!(params.axis.norm() > 0)) TT_THROW(InvalidInput, "pattern: zero axis");
  BoundingBox box;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    if (!positions[i].allFinite()) TT_THROW(InvalidInput, "pattern: vertex " << i << " is not finite");
    box.extend(positions[i]);
  }
  double cell = params.cell;
  if (!(cell > 0)) cell = box.diagonal() > 0 ? box.diagonal() / 8 : 1.0;
  const Vec3 axis = params.axis.normalized();
  std::vector<float> out(positions.size() * w);
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const Vec3 q = positions[i] - params.origin;
    double t = 0;  // share of b
    switch (params.kind) {
      case PatternKind::Checker: {
        const long s = long(std::floor(q.x() / cell)) + long(std::floor(q.y() / cell)) + long(std::floor(q.z() / cell));
        t = (s & 1) ? 1 : 0;
        break;
      }
      case PatternKind::Stripes:
        t = (long(std::floor(q.dot(axis) / cell)) & 1) ? 1 : 0;
        break;
      case PatternKind::Sine:
        t = 0.5 * (1 + std::sin(std::numbers::pi * q.dot(axis) / cell));
        break;
      case PatternKind::Constant:
        t = 0;
        break;
    }
    for (std::size_t c = 0; c < w; ++c) out[i * w + c] = float((1 - t) * params.a[c] + t * params.b[c]);
  }
  return out;
}

std::vector<float> blend_fields(std::span<const float> a, std::span<const float> b, double t) {
  if (a.size() != b.size()) TT_THROW(InvalidInput, "blend_fields: sizes " << a.size() << " and " << b.size());
  std::vector<float> out(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) out[i] = float((1 - t) * a[i] + t * b[i]);
  return out;
}

}  // namespace topotrack
