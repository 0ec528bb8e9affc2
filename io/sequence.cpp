#include "io/sequence.hpp"

#include <algorithm>
#include <cctype>
#include <map>
#include <numeric>
#include <optional>
#include <system_error>

#include "io/error.hpp"

namespace topotrack {

namespace fs = std::filesystem;

namespace {

constexpr std::size_t kMaxFrameDigits = 18;  // fits a long without overflow
constexpr std::size_t kMaxGapWarnings = 10;

bool is_digit(char c) { return c >= '0' && c <= '9'; }

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

bool is_frame_extension(const fs::path& p) {
  const std::string ext = lower(p.extension().string());
  return ext == ".obj" || ext == ".ply" || ext == ".vdb";
}

long digits_value(std::string_view d) {
  long v = 0;
  for (char c : d) v = v * 10 + (c - '0');
  return v;
}

// The last run of digits in the file name before its extension, or -1.
long frame_number_of(const fs::path& p) {
  const std::string stem = p.stem().string();
  std::size_t e = stem.size();
  while (e > 0 && !is_digit(stem[e - 1])) --e;
  std::size_t b = e;
  while (b > 0 && is_digit(stem[b - 1])) --b;
  if (b == e || e - b > kMaxFrameDigits) return -1;
  return digits_value(std::string_view(stem).substr(b, e - b));
}

// Natural order: runs of digits compare by value, the rest byte by byte.
bool natural_less(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (is_digit(a[i]) && is_digit(b[j])) {
      std::size_t ie = i, je = j;
      while (ie < a.size() && is_digit(a[ie])) ++ie;
      while (je < b.size() && is_digit(b[je])) ++je;
      std::size_t iz = i, jz = j;  // skip leading zeros, then longer run is larger
      while (iz + 1 < ie && a[iz] == '0') ++iz;
      while (jz + 1 < je && b[jz] == '0') ++jz;
      if (ie - iz != je - jz) return ie - iz < je - jz;
      const int c = a.compare(iz, ie - iz, b, jz, je - jz);
      if (c != 0) return c < 0;
      if (ie - i != je - j) return ie - i > je - j;  // more padding first, for a total order
      i = ie;
      j = je;
      continue;
    }
    if (a[i] != b[j]) return static_cast<unsigned char>(a[i]) < static_cast<unsigned char>(b[j]);
    ++i;
    ++j;
  }
  return a.size() - i < b.size() - j;
}

// A file-name pattern: literals, '*', '?', and at most one frame-number field.
struct Token {
  enum Kind { Literal, Star, Any, Frame } kind;
  std::string text;  // Literal
  int width = 0;     // Frame: 0 = any number of digits, else zero-padded to at least this width
};

struct Pattern {
  std::vector<Token> tokens;
  bool has_frame = false;
  bool has_wildcard = false;
};

// Parses the frame-field syntaxes: "####", "%04d"/"%d", "$F4"/"$F", "{}".
Pattern parse_pattern(const std::string& name, const std::string& spec) {
  Pattern pat;
  auto literal = [&](char c) {
    if (pat.tokens.empty() || pat.tokens.back().kind != Token::Literal)
      pat.tokens.push_back({Token::Literal, "", 0});
    pat.tokens.back().text += c;
  };
  auto frame = [&](int width) {
    if (pat.has_frame) TT_THROW(InvalidInput, spec << ": more than one frame-number field in the pattern");
    pat.has_frame = true;
    pat.tokens.push_back({Token::Frame, "", width});
  };
  for (std::size_t i = 0; i < name.size();) {
    const char c = name[i];
    if (c == '#') {
      std::size_t e = i;
      while (e < name.size() && name[e] == '#') ++e;
      frame(static_cast<int>(e - i));
      i = e;
    } else if (c == '%') {
      std::size_t e = i + 1;
      while (e < name.size() && is_digit(name[e])) ++e;
      if (e < name.size() && name[e] == 'd') {
        frame(e > i + 1 ? static_cast<int>(digits_value(
                              std::string_view(name).substr(i + 1, std::min<std::size_t>(e - i - 1, 3))))
                        : 0);
        i = e + 1;
      } else {
        literal(c);
        ++i;
      }
    } else if (c == '$' && i + 1 < name.size() && name[i + 1] == 'F') {
      std::size_t e = i + 2;
      while (e < name.size() && is_digit(name[e])) ++e;
      frame(e > i + 2 ? static_cast<int>(digits_value(
                            std::string_view(name).substr(i + 2, std::min<std::size_t>(e - i - 2, 3))))
                      : 0);
      i = e;
    } else if (c == '{' && i + 1 < name.size() && name[i + 1] == '}') {
      frame(0);
      i += 2;
    } else if (c == '*') {
      pat.has_wildcard = true;
      pat.tokens.push_back({Token::Star, "", 0});
      ++i;
    } else if (c == '?') {
      pat.has_wildcard = true;
      pat.tokens.push_back({Token::Any, "", 0});
      ++i;
    } else {
      literal(c);
      ++i;
    }
  }
  return pat;
}

// Matches name[i..] against tokens[t..]; on success sets `number` from the frame field (backtracking over '*'
// and the digit count of an unpadded field).
bool match(const Pattern& pat, std::size_t t, const std::string& name, std::size_t i, long& number) {
  if (t == pat.tokens.size()) return i == name.size();
  const Token& tok = pat.tokens[t];
  switch (tok.kind) {
    case Token::Literal:
      return name.compare(i, tok.text.size(), tok.text) == 0 &&
             match(pat, t + 1, name, i + tok.text.size(), number);
    case Token::Any:
      return i < name.size() && match(pat, t + 1, name, i + 1, number);
    case Token::Star:
      for (std::size_t k = i; k <= name.size(); ++k)
        if (match(pat, t + 1, name, k, number)) return true;
      return false;
    case Token::Frame: {
      std::size_t e = i;
      while (e < name.size() && is_digit(name[e])) ++e;
      for (std::size_t k = e; k > i; --k) {  // longest digit run first
        const std::size_t n = k - i;
        if (n > kMaxFrameDigits) continue;
        // Padded: exactly `width` digits, or more without a leading zero (frame 12345 of "####").
        if (tok.width > 0 && !(n == static_cast<std::size_t>(tok.width) ||
                               (n > static_cast<std::size_t>(tok.width) && name[i] != '0')))
          continue;
        if (match(pat, t + 1, name, k, number)) {
          number = digits_value(std::string_view(name).substr(i, n));
          return true;
        }
      }
      return false;
    }
  }
  return false;
}

void sort_and_check(FrameSequence& seq, const std::string& spec) {
  std::sort(seq.frames.begin(), seq.frames.end(), [](const SequenceFrame& a, const SequenceFrame& b) {
    if (a.number != b.number) return a.number < b.number;
    return natural_less(a.path.filename().string(), b.path.filename().string());
  });
  for (std::size_t k = 1; k < seq.frames.size(); ++k)
    if (seq.frames[k].number >= 0 && seq.frames[k].number == seq.frames[k - 1].number)
      TT_THROW(InvalidInput, spec << ": frame number " << seq.frames[k].number
                                  << " appears twice: " << seq.frames[k - 1].path.filename().string()
                                  << " and " << seq.frames[k].path.filename().string());

  std::vector<long> numbers;
  std::size_t unnumbered = 0;
  for (const auto& f : seq.frames) {
    if (f.number >= 0)
      numbers.push_back(f.number);
    else
      ++unnumbered;
  }
  if (unnumbered > 0 && !numbers.empty())
    seq.warnings.push_back(spec + ": " + std::to_string(unnumbered) +
                           " file(s) without a frame number come first, in name order");
  // The step is the gcd of the differences, so frames 0, 10, 20 are a sequence with step 10, not gaps.
  long step = 0;
  for (std::size_t k = 1; k < numbers.size(); ++k) step = std::gcd(step, numbers[k] - numbers[k - 1]);
  std::size_t gaps = 0;
  for (std::size_t k = 1; k < numbers.size(); ++k) {
    const long d = numbers[k] - numbers[k - 1];
    if (d <= step) continue;
    if (++gaps <= kMaxGapWarnings) {
      const long missing = d / step - 1;
      seq.warnings.push_back(spec + ": gap in the frame numbers: " + std::to_string(missing) +
                             " frame(s) missing between " + std::to_string(numbers[k - 1]) + " and " +
                             std::to_string(numbers[k]));
    }
  }
  if (gaps > kMaxGapWarnings)
    seq.warnings.push_back(spec + ": " + std::to_string(gaps - kMaxGapWarnings) +
                           " further gap(s) not listed");

  std::map<std::string, std::size_t> formats;
  for (const auto& f : seq.frames) ++formats[lower(f.path.extension().string())];
  if (formats.size() > 1) {
    std::string w = spec + ": mixed file formats:";
    for (const auto& [ext, n] : formats)
      w.append(" ").append(std::to_string(n)).append(" x ").append(ext.empty() ? "(none)" : ext);
    seq.warnings.push_back(w);
  }
}

// Regular files (or symlinks to them) in `dir`, by name; hidden files (temporaries of atomic writes) skipped.
std::vector<fs::path> list_files(const fs::path& dir, const std::string& spec) {
  std::vector<fs::path> files;
  std::error_code ec;
  fs::directory_iterator it(dir, ec);
  if (ec) TT_THROW(IoError, spec << ": cannot list folder: " << ec.message());
  for (const fs::directory_iterator end; it != end; it.increment(ec)) {
    if (ec) TT_THROW(IoError, spec << ": cannot list folder: " << ec.message());
    const std::string name = it->path().filename().string();
    if (name.empty() || name[0] == '.') continue;
    std::error_code fec;
    if (!it->is_regular_file(fec)) continue;
    files.push_back(it->path());
  }
  return files;
}

}  // namespace

FrameSequence find_frames(const std::string& spec) {
  if (spec.empty()) TT_THROW(InvalidInput, "empty sequence specification");
  FrameSequence seq;
  std::error_code ec;
  const fs::path path(spec);

  if (fs::is_directory(path, ec)) {
    for (const fs::path& f : list_files(path, spec))
      if (is_frame_extension(f)) seq.frames.push_back({f, frame_number_of(f)});
    if (seq.frames.empty()) TT_THROW(InvalidInput, spec << ": no .obj, .ply or .vdb files in the folder");
    sort_and_check(seq, spec);
    return seq;
  }

  const std::string name = path.filename().string();
  const Pattern pat = parse_pattern(name, spec);
  if (!pat.has_frame && !pat.has_wildcard) {
    // A plain path: one frame, read (and failing) as a file; a missing one is reported here.
    if (!fs::exists(fs::symlink_status(path, ec))) TT_THROW(InvalidInput, spec << ": no such file or folder");
    seq.frames.push_back({path, frame_number_of(path)});
    return seq;
  }
  const fs::path dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  if (!fs::is_directory(dir, ec))
    TT_THROW(InvalidInput, spec << ": folder '" << dir.string() << "' does not exist");
  for (const fs::path& f : list_files(dir, spec)) {
    long number = -1;
    if (!match(pat, 0, f.filename().string(), 0, number)) continue;
    if (!pat.has_frame) number = frame_number_of(f);
    seq.frames.push_back({path.parent_path().empty() ? f.filename() : f, number});
  }
  if (seq.frames.empty()) TT_THROW(InvalidInput, spec << ": no file matches the pattern");
  sort_and_check(seq, spec);
  return seq;
}

}  // namespace topotrack
