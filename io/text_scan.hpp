#pragma once
//! Internal to io/: locale-free number scanning shared by the OBJ and ASCII PLY readers.
//! Numbers go through fast_float (floating point) and std::from_chars (integers): both ignore the
//! C locale (strtod would read "1,5" under a German locale and is several times slower), never
//! allocate, and report exactly where the number ended, so a reader can reject "1.5abc".
#include <fast_float/fast_float.h>

#include <charconv>
#include <cstdint>
#include <string>
#include <string_view>
#include <system_error>

namespace topotrack::text {

inline bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }
inline bool is_space_or_newline(char c) { return is_space(c) || c == '\n'; }
inline bool is_digit(char c) { return c >= '0' && c <= '9'; }

//! Skip blanks (not newlines).
inline const char* skip_blanks(const char* p, const char* end) {
  while (p < end && is_space(*p)) ++p;
  return p;
}

//! Parse a double at [p, end); on success advance p. A leading '+' is accepted (fast_float rejects it).
inline bool parse_double(const char*& p, const char* end, double& out) {
  const char* q = p;
  if (q < end && *q == '+' && ++q < end && *q == '-') return false;
  const auto r = fast_float::from_chars(q, end, out);
  if (r.ec != std::errc()) return false;
  p = r.ptr;
  return true;
}

//! Parse a signed integer at [p, end); on success advance p.
inline bool parse_int(const char*& p, const char* end, std::int64_t& out) {
  const char* q = p;
  if (q < end && *q == '+' && ++q < end && *q == '-') return false;
  const auto r = std::from_chars(q, end, out);
  if (r.ec != std::errc()) return false;
  p = r.ptr;
  return true;
}

//! A token quoted in an error message: at most `max` bytes, anything but printable ASCII as \xNN, so a
//! binary file does not write raw bytes to the terminal.
inline std::string printable(std::string_view token, std::size_t max = 40) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  for (std::size_t i = 0; i < token.size() && i < max; ++i) {
    const auto c = static_cast<unsigned char>(token[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  if (token.size() > max) out += "...";
  return out;
}

}  // namespace topotrack::text
