#include "io/event_file.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>

#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "io/mapped_file.hpp"

namespace topotrack {

namespace {

//! FNV-1a 64, fed piece by piece as the bytes are produced.
struct Fnv1a {
  std::uint64_t h = 0xcbf29ce484222325ull;
  void add(std::string_view bytes) {
    for (unsigned char c : bytes) {
      h ^= c;
      h *= 0x100000001b3ull;
    }
  }
};

}  // namespace

std::uint64_t event_file_checksum(std::string_view bytes) {
  Fnv1a sum;
  sum.add(bytes);
  return sum.h;
}

namespace {

// Layout (docs/formats.md, "Event list file"): all integers little endian, no padding.
constexpr char kMagic[8] = {'T', 'T', 'E', 'V', 'E', 'N', 'T', 'S'};
constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kHeaderBytes = 8 + 4 + 4 + 4 * 8;
constexpr std::size_t kEventHeadBytes = 1 + 4 * 4;
constexpr std::size_t kRuleHeadBytes = 8 + 4;
constexpr std::size_t kTermBytes = 8 + 8;
constexpr std::size_t kChecksumBytes = 8;
// encode_events hands its bytes on in pieces of about this size: a file is never held whole in memory (a
// frame's list on a fine lattice is ~100 MB: resurfaced pcow, capture profile, two halvings).
constexpr std::size_t kPieceBytes = 1 << 20;

template <class T>
void put(std::string& s, T v) {
  static_assert(std::is_trivially_copyable_v<T>);
  if constexpr (std::endian::native == std::endian::big && sizeof(T) > 1) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    s.append(b, sizeof(T));
  } else {
    s.append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
}

class Reader {
 public:
  Reader(std::string_view bytes, const std::string& name) : b_(bytes), name_(name) {}

  [[noreturn]] void fail_at(std::size_t offset, const std::string& what) const {
    TT_THROW(InvalidInput, name_ << ": byte " << offset << ": " << what);
  }
  std::size_t offset() const { return pos_; }
  std::size_t remaining() const { return end_ - pos_; }
  void set_end(std::size_t end) { end_ = end; }

  template <class T>
  T get(const char* what) {
    if (remaining() < sizeof(T)) fail_at(pos_, std::string("truncated: file ends inside ") + what);
    T v;
    char b[sizeof(T)];
    std::memcpy(b, b_.data() + pos_, sizeof(T));
    if constexpr (std::endian::native == std::endian::big && sizeof(T) > 1)
      for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    std::memcpy(&v, b, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  // A count of records of at least `min_bytes` each: rejected before anything is allocated for it if the
  // remaining bytes cannot hold that many.
  std::uint64_t count(const char* what, std::size_t min_bytes) {
    const std::size_t at = pos_;
    const auto n = get<std::uint32_t>(what);
    if (n > remaining() / min_bytes)
      fail_at(at, std::string(what) + " " + std::to_string(n) + " exceeds what the remaining " +
                      std::to_string(remaining()) + " bytes can hold");
    return n;
  }

 private:
  std::string_view b_;
  const std::string& name_;
  std::size_t pos_ = 0;
  std::size_t end_ = 0;
};

}  // namespace

void encode_events(const EventList& events, const std::function<void(std::string_view)>& emit) {
  std::string s;
  s.reserve(kPieceBytes + kPieceBytes / 4);
  Fnv1a sum;
  const auto hand_on = [&] {
    sum.add(s);
    emit(s);
    s.clear();
  };
  s.append(kMagic, sizeof kMagic);
  put<std::uint32_t>(s, kVersion);
  put<std::uint32_t>(s, 0);  // flags, reserved
  std::uint64_t ids = 0;
  for (std::size_t e = 0; e < events.size(); ++e) {
    const auto v = events.event(e);
    ids += v.in.size() + v.out.size();
  }
  put<std::uint64_t>(s, events.size());
  put<std::uint64_t>(s, ids);
  put<std::uint64_t>(s, events.rule_count());
  put<std::uint64_t>(s, events.term_count());
  auto rule = [&](std::size_t r) {
    const EventList::Rule rr = events.rule(r);
    put<std::uint64_t>(s, rr.target);
    put<std::uint32_t>(s, static_cast<std::uint32_t>(rr.terms.size()));
    for (const RuleTerm& t : rr.terms) {
      if (!std::isfinite(t.weight))
        TT_THROW(InvalidInput, "event list: rule " << r << " has a non-finite weight " << t.weight);
      put<std::uint64_t>(s, t.source);
      put<double>(s, t.weight);
    }
  };
  for (std::size_t e = 0; e < events.size(); ++e) {
    const auto v = events.event(e);
    put<std::uint8_t>(s, static_cast<std::uint8_t>(v.kind));
    put<std::uint32_t>(s, static_cast<std::uint32_t>(v.in.size()));
    put<std::uint32_t>(s, static_cast<std::uint32_t>(v.out.size()));
    put<std::uint32_t>(s, static_cast<std::uint32_t>(v.forward_end - v.forward_begin));
    put<std::uint32_t>(s, static_cast<std::uint32_t>(v.backward_end - v.backward_begin));
    for (VertexId id : v.in) put<std::uint64_t>(s, id);
    for (VertexId id : v.out) put<std::uint64_t>(s, id);
    for (std::size_t r = v.forward_begin; r < v.forward_end; ++r) rule(r);
    for (std::size_t r = v.backward_begin; r < v.backward_end; ++r) rule(r);
    if (s.size() >= kPieceBytes) hand_on();
  }
  hand_on();
  put<std::uint64_t>(s, sum.h);
  emit(s);
}

std::string encode_events(const EventList& events) {
  std::string bytes;
  bytes.reserve(kHeaderBytes + events.size() * kEventHeadBytes + events.rule_count() * kRuleHeadBytes +
                events.term_count() * kTermBytes + kChecksumBytes);
  encode_events(events, [&](std::string_view piece) { bytes.append(piece); });
  return bytes;
}

EventList decode_events(std::string_view bytes, const std::string& name) {
  Reader in(bytes, name);
  in.set_end(bytes.size());
  if (bytes.empty()) in.fail_at(0, "empty file");
  if (bytes.size() < sizeof kMagic || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    in.fail_at(0, "not a topotrack event file (bad magic)");
  for (int i = 0; i < 8; ++i) in.get<char>("the magic");
  const auto version = in.get<std::uint32_t>("the header");
  if (version != kVersion)
    in.fail_at(8, "unsupported event file version " + std::to_string(version) + " (this build reads " +
                      std::to_string(kVersion) + ")");
  const auto flags = in.get<std::uint32_t>("the header");
  if (flags != 0) in.fail_at(12, "unknown flags " + std::to_string(flags));
  const auto n_events = in.get<std::uint64_t>("the header");
  const auto n_ids = in.get<std::uint64_t>("the header");
  const auto n_rules = in.get<std::uint64_t>("the header");
  const auto n_terms = in.get<std::uint64_t>("the header");
  if (bytes.size() < kHeaderBytes + kChecksumBytes)
    in.fail_at(bytes.size(), "truncated: no room for the checksum");
  const std::size_t body_end = bytes.size() - kChecksumBytes;
  {
    Reader tail(bytes.substr(body_end), name);
    tail.set_end(kChecksumBytes);
    const auto stored = tail.get<std::uint64_t>("the checksum");
    if (stored != event_file_checksum(bytes.substr(0, body_end)))
      in.fail_at(body_end, "checksum mismatch: the file is corrupt or truncated");
  }
  // Never trust the totals: each must fit in what the body can hold (EventList indexes with 32 bits).
  const std::size_t body = body_end - kHeaderBytes;
  const auto lim32 = static_cast<std::uint64_t>(std::numeric_limits<std::uint32_t>::max());
  if (n_events > body / kEventHeadBytes || n_ids > body / 8 || n_rules > body / kRuleHeadBytes ||
      n_terms > body / kTermBytes || n_ids > lim32 || n_rules > lim32 || n_terms > lim32)
    in.fail_at(16, "header counts (" + std::to_string(n_events) + " events, " + std::to_string(n_ids) +
                       " ids, " + std::to_string(n_rules) + " rules, " + std::to_string(n_terms) +
                       " terms) exceed the file size");
  in.set_end(body_end);

  EventList list;
  std::uint64_t ids = 0, rules = 0, terms = 0;
  std::vector<RuleTerm> buf;
  for (std::uint64_t e = 0; e < n_events; ++e) {
    const std::size_t at = in.offset();
    const auto kind = in.get<std::uint8_t>("an event");
    if (kind < 1 || kind > kEventKindCount)
      in.fail_at(at, "event " + std::to_string(e) + " has unknown kind " + std::to_string(kind));
    const std::uint64_t n_in = in.count("V_in size", 8);
    const std::uint64_t n_out = in.count("V_out size", 8);
    const std::uint64_t n_fwd = in.count("forward rule count", kRuleHeadBytes);
    const std::uint64_t n_bwd = in.count("backward rule count", kRuleHeadBytes);
    ids += n_in + n_out;
    rules += n_fwd + n_bwd;
    if (ids > n_ids || rules > n_rules)
      in.fail_at(at, "event " + std::to_string(e) + " exceeds the id or rule total of the header");
    list.begin_event(static_cast<EventKind>(kind));
    for (std::uint64_t i = 0; i < n_in; ++i) list.add_in(in.get<std::uint64_t>("V_in"));
    for (std::uint64_t i = 0; i < n_out; ++i) list.add_out(in.get<std::uint64_t>("V_out"));
    for (std::uint64_t r = 0; r < n_fwd + n_bwd; ++r) {
      const auto target = in.get<std::uint64_t>("a rule");
      const std::size_t count_at = in.offset();
      const std::uint64_t nt = in.count("term count", kTermBytes);
      terms += nt;
      if (terms > n_terms) in.fail_at(count_at, "rule exceeds the term total of the header");
      buf.resize(nt);
      for (auto& t : buf) {
        t.source = in.get<std::uint64_t>("a rule term");
        const std::size_t w_at = in.offset();
        t.weight = in.get<double>("a rule term");
        if (!std::isfinite(t.weight)) in.fail_at(w_at, "non-finite rule weight");
      }
      if (r < n_fwd)
        list.add_forward_rule(target, buf);
      else
        list.add_backward_rule(target, buf);
    }
    list.end_event();
  }
  if (ids != n_ids || rules != n_rules || terms != n_terms)
    in.fail_at(in.offset(), "the records hold " + std::to_string(ids) + " ids, " + std::to_string(rules) +
                                " rules, " + std::to_string(terms) + " terms but the header says " +
                                std::to_string(n_ids) + ", " + std::to_string(n_rules) + ", " +
                                std::to_string(n_terms));
  if (in.offset() != body_end)
    in.fail_at(in.offset(), std::to_string(body_end - in.offset()) + " trailing bytes after the last event");
  return list;
}

void write_events(const std::filesystem::path& path, const EventList& events) {
  try {
    write_file_atomic(path, [&](AtomicFileWriter& w) {
      encode_events(events, [&](std::string_view piece) { w.write(piece); });
    });
  } catch (const InvalidInput& e) {  // the file is untouched (the temporary one removed)
    TT_THROW(InvalidInput, path.string() << ": " << e.what());
  }
}

EventList read_events(const std::filesystem::path& path) {
  const MappedFile file(path);
  return decode_events(file.text(), path.string());
}

}  // namespace topotrack
