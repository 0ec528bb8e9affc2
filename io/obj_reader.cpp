#include "io/obj_reader.hpp"

#include <cmath>
#include <cstring>
#include <vector>

#include "io/error.hpp"
#include "io/mapped_file.hpp"
#include "io/text_scan.hpp"

namespace topotrack {

namespace {

using text::is_space;

// One line of OBJ text without its newline; `#` starts a comment.
struct Line {
  const char* p;
  const char* end;
  std::size_t number;
};

class ObjParser {
public:
  ObjParser(std::string_view text, const std::string& name) : text_(text), name_(name) {}

  MeshData run() {
    if (text_.empty()) TT_THROW(InvalidInput, name_ << ": empty file");
    const char* p = text_.data();
    const char* const end = p + text_.size();
    std::size_t number = 1;
    while (p < end) {
      const char* eol = static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(end - p)));
      if (!eol) eol = end;
      statement(Line{p, eol, number});
      p = eol + 1;
      ++number;
    }
    finish();
    return std::move(mesh_);
  }

private:
  [[noreturn]] void fail(std::size_t line, const std::string& what) const {
    TT_THROW(InvalidInput, name_ << ":" << line << ": " << what);
  }
  static std::string token_at(const char* p, const char* end) {
    const char* q = p;
    while (q < end && !is_space(*q)) ++q;
    return text::printable(std::string_view(p, static_cast<std::size_t>(q - p)));
  }
  static const char* comment_start(const char* p, const char* end) {
    const char* hash = static_cast<const char*>(std::memchr(p, '#', static_cast<std::size_t>(end - p)));
    return hash ? hash : end;
  }

  void statement(Line l) {
    const char* p = text::skip_blanks(l.p, l.end);
    if (p == l.end || (p[0] != 'v' && p[0] != 'f')) return;  // blank, comment, other statement
    if (p + 1 < l.end && !is_space(p[1])) return;              // vt, vn, vp, fo, ...
    const Line args{p + 1, comment_start(p + 1, l.end), l.number};
    if (p[0] == 'v') vertex(args);
    else face(args);
  }

  void vertex(Line l) {
    std::array<double, 3> x{};
    const char* p = l.p;
    int n = 0;
    for (;; ++n) {
      p = text::skip_blanks(p, l.end);
      if (p == l.end) break;
      double value = 0;
      const char* start = p;
      if (!text::parse_double(p, l.end, value) || (p < l.end && !is_space(*p)))
        fail(l.number, "non-numeric token '" + token_at(start, l.end) + "' in vertex");
      if (n < 3) {
        if (!std::isfinite(value)) fail(l.number, "non-finite vertex coordinate '" + token_at(start, l.end) + "'");
        x[n] = value;
      }
    }
    if (n < 3) fail(l.number, "vertex with " + std::to_string(n) + " coordinates (need x y z)");
    mesh_.positions.push_back(x);
  }

  // One corner `v`, `v/vt`, `v//vn` or `v/vt/vn`; returns the 0-based vertex index.
  std::int64_t corner(const char*& p, const char* end, std::size_t line) {
    const char* start = p;
    std::int64_t index[3] = {0, 0, 0};
    int field = 0;
    for (;;) {
      if (p < end && *p != '/' && !is_space(*p) && !text::parse_int(p, end, index[field]))
        fail(line, "non-numeric face corner '" + token_at(start, end) + "'");
      if (p == end || is_space(*p)) break;
      if (*p != '/' || field == 2) fail(line, "bad face corner '" + token_at(start, end) + "'");
      ++p;
      ++field;
    }
    const std::int64_t i = index[0];
    const auto defined = static_cast<std::int64_t>(mesh_.positions.size());
    if (i == 0) fail(line, "face corner '" + token_at(start, end) + "' has vertex index 0 (OBJ is 1-based)");
    if (i < 0) {
      if (i < -defined)  // not -i > defined: -i overflows for INT64_MIN
        fail(line, "relative index " + std::to_string(i) + " before the first vertex (" +
                       std::to_string(defined) + " defined)");
      return defined + i;
    }
    if (i > defined && i > max_forward_) {  // forward reference: checked once all vertices are known
      max_forward_ = i;
      max_forward_line_ = line;
    }
    return i - 1;
  }

  void face(Line l) {
    corners_.clear();
    const char* p = l.p;
    for (;;) {
      p = text::skip_blanks(p, l.end);
      if (p == l.end) break;
      corners_.push_back(corner(p, l.end, l.number));
    }
    if (corners_.size() < 3)
      fail(l.number, "face with " + std::to_string(corners_.size()) + " vertices (need at least 3)");
    for (std::size_t k = 1; k + 1 < corners_.size(); ++k)
      mesh_.triangles.push_back({corners_[0], corners_[k], corners_[k + 1]});
  }

  void finish() {
    if (mesh_.positions.empty()) TT_THROW(InvalidInput, name_ << ": no vertices");
    if (max_forward_ > static_cast<std::int64_t>(mesh_.positions.size()))
      fail(max_forward_line_, "vertex index " + std::to_string(max_forward_) + " out of range (" +
                                  std::to_string(mesh_.positions.size()) + " vertices)");
  }

  std::string_view text_;
  const std::string& name_;
  MeshData mesh_;
  std::vector<std::int64_t> corners_;
  std::int64_t max_forward_ = 0;
  std::size_t max_forward_line_ = 0;
};

}  // namespace

MeshData parse_obj(std::string_view text, const std::string& name) { return ObjParser(text, name).run(); }

MeshData read_obj(const std::filesystem::path& path) {
  const MappedFile file(path);
  return parse_obj(file.text(), path.string());
}

}  // namespace topotrack
