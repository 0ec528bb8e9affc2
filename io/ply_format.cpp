#include "io/ply_format.hpp"

#include <array>
#include <charconv>
#include <cstring>
#include <utility>

#include "io/error.hpp"

namespace topotrack {

namespace {

struct TypeName {
  std::string_view name;
  PlyScalar type;
};
constexpr std::array<TypeName, 20> kTypeNames{{
    {"char", PlyScalar::I8},     {"int8", PlyScalar::I8},      {"uchar", PlyScalar::U8},
    {"uint8", PlyScalar::U8},    {"short", PlyScalar::I16},    {"int16", PlyScalar::I16},
    {"ushort", PlyScalar::U16},  {"uint16", PlyScalar::U16},   {"int", PlyScalar::I32},
    {"int32", PlyScalar::I32},   {"uint", PlyScalar::U32},     {"uint32", PlyScalar::U32},
    {"int64", PlyScalar::I64},   {"uint64", PlyScalar::U64},   {"float", PlyScalar::F32},
    {"float32", PlyScalar::F32}, {"double", PlyScalar::F64},   {"float64", PlyScalar::F64},
    {"long", PlyScalar::I64},    {"ulong", PlyScalar::U64},
}};

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

// Whitespace-separated words of one header line.
std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_blank(line[i])) ++i;
    const std::size_t b = i;
    while (i < line.size() && !is_blank(line[i])) ++i;
    if (i > b) words.push_back(line.substr(b, i - b));
  }
  return words;
}

class HeaderParser {
public:
  HeaderParser(std::string_view bytes, const std::string& name) : bytes_(bytes), name_(name) {}

  PlyHeader run() {
    if (bytes_.empty()) TT_THROW(InvalidInput, name_ << ": empty file");
    std::string_view line;
    if (!next_line(line) || split_words(line) != std::vector<std::string_view>{"ply"})
      fail("not a PLY file (first line is not 'ply')");
    bool have_format = false;
    while (next_line(line)) {
      const auto w = split_words(line);
      if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
      if (w[0] == "end_header") {
        if (!have_format) fail("no 'format' line before end_header");
        header_.body_offset = pos_;
        header_.body_line = line_ + 1;
        return std::move(header_);
      }
      if (w[0] == "format") {
        format(w);
        have_format = true;
      } else if (w[0] == "element") {
        element(w);
      } else if (w[0] == "property") {
        property(w);
      } else {
        fail("unknown header keyword '" + std::string(w[0]) + "'");
      }
    }
    TT_THROW(InvalidInput, name_ << ":" << line_ << ": header without end_header");
  }

private:
  [[noreturn]] void fail(const std::string& what) const {
    TT_THROW(InvalidInput, name_ << ":" << line_ << ": " << what);
  }

  bool next_line(std::string_view& line) {
    if (pos_ >= bytes_.size()) return false;
    const std::size_t nl = bytes_.find('\n', pos_);
    const std::size_t end = nl == std::string_view::npos ? bytes_.size() : nl;
    line = bytes_.substr(pos_, end - pos_);
    pos_ = nl == std::string_view::npos ? bytes_.size() : nl + 1;
    ++line_;
    return true;
  }

  PlyScalar scalar(std::string_view word) const {
    for (const auto& t : kTypeNames)
      if (t.name == word) return t.type;
    fail("unknown property type '" + std::string(word) + "'");
  }

  void format(const std::vector<std::string_view>& w) {
    if (w.size() < 2) fail("format line without a format");
    if (w[1] == "ascii") header_.format = PlyFormat::Ascii;
    else if (w[1] == "binary_little_endian") header_.format = PlyFormat::BinaryLittleEndian;
    else if (w[1] == "binary_big_endian") header_.format = PlyFormat::BinaryBigEndian;
    else fail("unknown format '" + std::string(w[1]) + "'");
  }

  void element(const std::vector<std::string_view>& w) {
    if (w.size() != 3) fail("element line needs a name and a count");
    PlyElement e;
    e.name = std::string(w[1]);
    e.line = line_;
    const auto r = std::from_chars(w[2].data(), w[2].data() + w[2].size(), e.count);
    if (r.ec != std::errc() || r.ptr != w[2].data() + w[2].size())
      fail("bad element count '" + std::string(w[2]) + "'");
    header_.elements.push_back(std::move(e));
  }

  void property(const std::vector<std::string_view>& w) {
    if (header_.elements.empty()) fail("property before any element");
    PlyProperty p;
    if (w.size() == 5 && w[1] == "list") {
      p.is_list = true;
      p.count_type = scalar(w[2]);
      if (ply_scalar_is_float(p.count_type)) fail("list count type must be an integer type");
      p.type = scalar(w[3]);
      p.name = std::string(w[4]);
    } else if (w.size() == 3 && w[1] != "list") {
      p.type = scalar(w[1]);
      p.name = std::string(w[2]);
    } else {
      fail("malformed property line");
    }
    header_.elements.back().properties.push_back(std::move(p));
  }

  std::string_view bytes_;
  const std::string& name_;
  std::size_t pos_ = 0;
  std::size_t line_ = 0;
  PlyHeader header_;
};

}  // namespace

std::size_t ply_scalar_size(PlyScalar t) {
  switch (t) {
    case PlyScalar::I8: case PlyScalar::U8: return 1;
    case PlyScalar::I16: case PlyScalar::U16: return 2;
    case PlyScalar::I32: case PlyScalar::U32: case PlyScalar::F32: return 4;
    case PlyScalar::I64: case PlyScalar::U64: case PlyScalar::F64: return 8;
  }
  return 0;
}

bool ply_scalar_is_float(PlyScalar t) { return t == PlyScalar::F32 || t == PlyScalar::F64; }

std::string_view to_string(PlyScalar t) {
  switch (t) {
    case PlyScalar::I8: return "char";
    case PlyScalar::U8: return "uchar";
    case PlyScalar::I16: return "short";
    case PlyScalar::U16: return "ushort";
    case PlyScalar::I32: return "int";
    case PlyScalar::U32: return "uint";
    case PlyScalar::I64: return "int64";
    case PlyScalar::U64: return "uint64";
    case PlyScalar::F32: return "float";
    case PlyScalar::F64: return "double";
  }
  return "?";
}

std::string_view to_string(PlyFormat f) {
  switch (f) {
    case PlyFormat::Ascii: return "ascii";
    case PlyFormat::BinaryLittleEndian: return "binary_little_endian";
    case PlyFormat::BinaryBigEndian: return "binary_big_endian";
  }
  return "?";
}

std::size_t PlyElement::fixed_stride() const {
  std::size_t stride = 0;
  for (const auto& p : properties) {
    if (p.is_list) return 0;
    stride += ply_scalar_size(p.type);
  }
  return stride;
}

int PlyElement::find(std::string_view n) const {
  for (std::size_t i = 0; i < properties.size(); ++i)
    if (properties[i].name == n) return static_cast<int>(i);
  return -1;
}

PlyHeader parse_ply_header(std::string_view bytes, const std::string& name) {
  return HeaderParser(bytes, name).run();
}

}  // namespace topotrack
