#pragma once
//! PLY header model and parser (shared by the PLY reader, the writer and tools that only peek).
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace topotrack {

//! Scalar types of PLY: the classic names (char uchar short ushort int uint float double), the sized
//! aliases (int8 uint8 int16 uint16 int32 uint32 float32 float64) and, as an extension, int64/uint64.
enum class PlyScalar : std::uint8_t { I8, U8, I16, U16, I32, U32, I64, U64, F32, F64 };
enum class PlyFormat : std::uint8_t { Ascii, BinaryLittleEndian, BinaryBigEndian };

std::size_t ply_scalar_size(PlyScalar t);
bool ply_scalar_is_float(PlyScalar t);
std::string_view to_string(PlyScalar t);
std::string_view to_string(PlyFormat f);

struct PlyProperty {
  std::string name;
  PlyScalar type = PlyScalar::F32;  //!< the item type of a list
  bool is_list = false;
  PlyScalar count_type = PlyScalar::U8;  //!< lists only
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  std::size_t line = 0;  //!< header line that declared it
  //! Bytes per record when every property is a scalar (binary), else 0.
  std::size_t fixed_stride() const;
  //! Index of the property with this name, or -1.
  int find(std::string_view name) const;
};

struct PlyHeader {
  PlyFormat format = PlyFormat::Ascii;
  std::vector<PlyElement> elements;
  std::size_t body_offset = 0;  //!< first byte after the end_header line
  std::size_t body_line = 0;    //!< line number of the first body line (ASCII)
};

//! Parse the header at the start of `bytes`. `comment` and `obj_info` lines are ignored.
//! \throw InvalidInput "<name>:<line>: <fault>": missing `ply` magic, missing or unknown `format`,
//!        unknown type or keyword, property before any element, bad count, no `end_header`.
PlyHeader parse_ply_header(std::string_view bytes, const std::string& name);

}  // namespace topotrack
