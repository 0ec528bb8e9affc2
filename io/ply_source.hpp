#pragma once
//! Internal to the PLY reader: sources of values for the body, one per encoding. Both check every
//! read against the end of the data and throw InvalidInput with the file name and the position
//! (byte offset for binary, line for ASCII).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>

#include "io/error.hpp"
#include "io/ply_format.hpp"
#include "io/text_scan.hpp"

namespace topotrack::ply_detail {

template <class T, bool Swap>
inline T load(const char* p) {
  T v;
  if constexpr (Swap && sizeof(T) > 1) {
    char b[sizeof(T)];
    std::memcpy(b, p, sizeof(T));
    std::reverse(b, b + sizeof(T));
    std::memcpy(&v, b, sizeof(T));
  } else {
    std::memcpy(&v, p, sizeof(T));
  }
  return v;
}

template <bool Swap>
inline double load_double(const char* p, PlyScalar t) {
  switch (t) {
    case PlyScalar::I8: return load<std::int8_t, Swap>(p);
    case PlyScalar::U8: return load<std::uint8_t, Swap>(p);
    case PlyScalar::I16: return load<std::int16_t, Swap>(p);
    case PlyScalar::U16: return load<std::uint16_t, Swap>(p);
    case PlyScalar::I32: return load<std::int32_t, Swap>(p);
    case PlyScalar::U32: return load<std::uint32_t, Swap>(p);
    case PlyScalar::I64: return static_cast<double>(load<std::int64_t, Swap>(p));
    case PlyScalar::U64: return static_cast<double>(load<std::uint64_t, Swap>(p));
    case PlyScalar::F32: return load<float, Swap>(p);
    case PlyScalar::F64: return load<double, Swap>(p);
  }
  return 0;
}

//! An integral double within int64 range, as int64; false otherwise (NaN, fraction, huge).
inline bool exact_int(double d, std::int64_t& out) {
  if (!(d >= -9.2e18 && d <= 9.2e18) || d != std::floor(d)) return false;
  out = static_cast<std::int64_t>(d);
  return true;
}

//! Integer value at p; false if it is not representable as int64 (uint64 above 2^63, float not integral).
template <bool Swap>
inline bool load_int(const char* p, PlyScalar t, std::int64_t& out) {
  switch (t) {
    case PlyScalar::I8: out = load<std::int8_t, Swap>(p); return true;
    case PlyScalar::U8: out = load<std::uint8_t, Swap>(p); return true;
    case PlyScalar::I16: out = load<std::int16_t, Swap>(p); return true;
    case PlyScalar::U16: out = load<std::uint16_t, Swap>(p); return true;
    case PlyScalar::I32: out = load<std::int32_t, Swap>(p); return true;
    case PlyScalar::U32: out = load<std::uint32_t, Swap>(p); return true;
    case PlyScalar::I64: out = load<std::int64_t, Swap>(p); return true;
    case PlyScalar::U64: {
      const auto u = load<std::uint64_t, Swap>(p);
      out = static_cast<std::int64_t>(u);
      return u <= static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max());
    }
    case PlyScalar::F32: return exact_int(load<float, Swap>(p), out);
    case PlyScalar::F64: return exact_int(load<double, Swap>(p), out);
  }
  return false;
}

//! Where the body reader is, for messages: element and record.
struct Position {
  const PlyElement* element = nullptr;
  std::uint64_t record = 0;
};

//! What both sources say when the data ends inside the element at `at`.
inline std::string truncated_message(const Position& at) {
  return "truncated data: file ends in element '" + at.element->name + "' (record " + std::to_string(at.record) +
         " of " + std::to_string(at.element->count) + ")";
}

//! A list's element count from either source: an integer, never negative.
template <class Source>
std::uint64_t read_list_count(Source& source, PlyScalar t) {
  const std::int64_t n = source.integer(t);
  if (n < 0) source.fail("negative list count " + std::to_string(n));
  return static_cast<std::uint64_t>(n);
}

template <bool Swap>
class BinarySource {
public:
  BinarySource(const char* data, std::size_t size, std::size_t pos, const std::string& name)
      : data_(data), size_(size), pos_(pos), last_(pos), name_(name) {}

  Position at;

  [[noreturn]] void fail_at(std::size_t offset, const std::string& what) const {
    TT_THROW(InvalidInput, name_ << ": byte " << offset << ": " << what);
  }
  [[noreturn]] void fail(const std::string& what) const { fail_at(last_, what); }
  [[noreturn]] void truncated(std::size_t offset) const { fail_at(offset, truncated_message(at)); }

  std::size_t remaining() const { return size_ - pos_; }
  std::size_t offset() const { return pos_; }
  const char* here() const { return data_ + pos_; }
  void advance(std::size_t n) { pos_ += n; }

  double scalar(PlyScalar t) { return load_double<Swap>(take(ply_scalar_size(t)), t); }
  std::int64_t integer(PlyScalar t) {
    std::int64_t v = 0;
    if (!load_int<Swap>(take(ply_scalar_size(t)), t, v)) fail("value is not an integer in int64 range");
    return v;
  }
  std::uint64_t list_count(PlyScalar t) { return read_list_count(*this, t); }
  void skip(PlyScalar t, std::uint64_t n) {
    const std::size_t s = ply_scalar_size(t);
    if (n > remaining() / s) truncated(size_);
    last_ = pos_;
    pos_ += n * s;
  }
  void finish() const {
    if (pos_ != size_)
      fail_at(pos_, std::to_string(size_ - pos_) + " trailing bytes after the last element");
  }

private:
  const char* take(std::size_t n) {
    if (remaining() < n) truncated(size_);
    last_ = pos_;
    pos_ += n;
    return data_ + last_;
  }

  const char* data_;
  std::size_t size_, pos_, last_;
  const std::string& name_;
};

class AsciiSource {
public:
  AsciiSource(const char* data, std::size_t size, std::size_t pos, std::size_t line, const std::string& name)
      : p_(data + pos), end_(data + size), line_(line), name_(name) {}

  Position at;

  [[noreturn]] void fail(const std::string& what) const {
    TT_THROW(InvalidInput, name_ << ":" << line_ << ": " << what);
  }
  std::size_t remaining() const { return static_cast<std::size_t>(end_ - p_); }

  double scalar(PlyScalar t) {
    if (!ply_scalar_is_float(t)) return static_cast<double>(integer(t));
    token();
    double v = 0;
    const char* q = tok_;
    if (!text::parse_double(q, tok_end_, v) || q != tok_end_) bad_token(t);
    return v;
  }
  std::int64_t integer(PlyScalar t) {
    token();
    std::int64_t v = 0;
    const char* q = tok_;
    if (ply_scalar_is_float(t)) {
      double d = 0;
      if (!text::parse_double(q, tok_end_, d) || q != tok_end_ || !exact_int(d, v)) bad_token(t);
      return v;
    }
    if (!text::parse_int(q, tok_end_, v) || q != tok_end_ || !in_range(v, t)) bad_token(t);
    return v;
  }
  std::uint64_t list_count(PlyScalar t) { return read_list_count(*this, t); }
  void skip(PlyScalar t, std::uint64_t n) {
    if (n > remaining()) truncated();
    for (std::uint64_t i = 0; i < n; ++i) scalar(t);
  }
  void finish() {
    skip_space();
    if (p_ != end_) fail("trailing data after the last element");
  }

private:
  static bool in_range(std::int64_t v, PlyScalar t) {
    switch (t) {
      case PlyScalar::I8: return v >= -128 && v <= 127;
      case PlyScalar::U8: return v >= 0 && v <= 255;
      case PlyScalar::I16: return v >= -32768 && v <= 32767;
      case PlyScalar::U16: return v >= 0 && v <= 65535;
      case PlyScalar::I32: return v >= -2147483648LL && v <= 2147483647LL;
      case PlyScalar::U32: return v >= 0 && v <= 4294967295LL;
      case PlyScalar::U64: return v >= 0;
      default: return true;
    }
  }
  [[noreturn]] void bad_token(PlyScalar t) const {
    fail("bad " + std::string(to_string(t)) + " value '" + text::printable(std::string_view(tok_, static_cast<std::size_t>(tok_end_ - tok_))) + "'");
  }
  [[noreturn]] void truncated() const { fail(truncated_message(at)); }
  void skip_space() {
    while (p_ < end_ && text::is_space_or_newline(*p_)) {
      if (*p_ == '\n') ++line_;
      ++p_;
    }
  }
  void token() {
    skip_space();
    if (p_ == end_) truncated();
    tok_ = p_;
    while (p_ < end_ && !text::is_space_or_newline(*p_)) ++p_;
    tok_end_ = p_;
  }

  const char* p_;
  const char* end_;
  const char* tok_ = nullptr;
  const char* tok_end_ = nullptr;
  std::size_t line_;
  const std::string& name_;
};

}  // namespace topotrack::ply_detail
