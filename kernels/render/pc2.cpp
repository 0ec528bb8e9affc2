#include "kernels/render/pc2.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <unordered_map>

#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "io/mapped_file.hpp"

namespace topotrack {

static_assert(std::endian::native == std::endian::little, "PC2 is little endian; add byte swapping");

namespace {
constexpr char kMagic[12] = {'P', 'O', 'I', 'N', 'T', 'C', 'A', 'C', 'H', 'E', '2', '\0'};

template <class T>
void put(std::string& s, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  s.append(b, sizeof(T));
}
template <class T>
T get(std::string_view s, std::size_t at) {
  T v;
  std::memcpy(&v, s.data() + at, sizeof(T));
  return v;
}
}  // namespace

Pc2Writer::Pc2Writer(const std::filesystem::path& path, const Pc2Header& header) : header_(header) {
  if (header.points < 1 || header.samples < 1)
    TT_THROW(InvalidInput, path.string() << ": PC2 needs at least one point and one sample (got " << header.points
                                         << " points, " << header.samples << " samples)");
  out_ = std::make_unique<AtomicFileWriter>(path);
  std::string h(kMagic, sizeof kMagic);
  put<std::int32_t>(h, 1);
  put<std::int32_t>(h, header.points);
  put<float>(h, header.start_frame);
  put<float>(h, header.sample_rate);
  put<std::int32_t>(h, header.samples);
  out_->write(h);
}

Pc2Writer::~Pc2Writer() = default;

void Pc2Writer::add_sample(std::span<const Vec3> positions) {
  if (positions.size() != std::size_t(header_.points))
    TT_THROW(InvalidInput, out_->target().string() << ": PC2 sample " << written_ << " has " << positions.size()
                                                   << " points, expected " << header_.points);
  if (written_ >= header_.samples)
    TT_THROW(InvalidInput, out_->target().string() << ": more than the " << header_.samples << " announced samples");
  buffer_.resize(3 * positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i)
    for (int c = 0; c < 3; ++c) buffer_[3 * i + c] = float(positions[i][c]);
  out_->write(std::string_view(reinterpret_cast<const char*>(buffer_.data()), buffer_.size() * sizeof(float)));
  ++written_;
}

void Pc2Writer::commit() {
  if (written_ != header_.samples)
    TT_THROW(InvalidInput, out_->target().string() << ": " << written_ << " PC2 samples written, " << header_.samples
                                                   << " announced");
  out_->commit();
}

Pc2Data decode_pc2(std::string_view bytes, const std::string& name) {
  if (bytes.size() < kPc2HeaderBytes) TT_THROW(InvalidInput, name << ": PC2 header truncated (" << bytes.size() << " bytes)");
  if (std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0) TT_THROW(InvalidInput, name << ": not a PC2 file (bad magic)");
  const auto version = get<std::int32_t>(bytes, 12);
  if (version != 1) TT_THROW(InvalidInput, name << ": unsupported PC2 version " << version);
  Pc2Data d;
  d.header.points = get<std::int32_t>(bytes, 16);
  d.header.start_frame = get<float>(bytes, 20);
  d.header.sample_rate = get<float>(bytes, 24);
  d.header.samples = get<std::int32_t>(bytes, 28);
  if (d.header.points < 0 || d.header.samples < 0)
    TT_THROW(InvalidInput, name << ": negative PC2 counts " << d.header.points << ", " << d.header.samples);
  const std::size_t n = std::size_t(d.header.points) * std::size_t(d.header.samples) * 3;
  if (bytes.size() != kPc2HeaderBytes + n * sizeof(float))
    TT_THROW(InvalidInput, name << ": PC2 of " << d.header.points << " points x " << d.header.samples
                                << " samples needs " << kPc2HeaderBytes + n * sizeof(float) << " bytes, file has "
                                << bytes.size());
  d.xyz.resize(n);
  std::memcpy(d.xyz.data(), bytes.data() + kPc2HeaderBytes, n * sizeof(float));
  return d;
}

Pc2Data read_pc2(const std::filesystem::path& path) {
  const MappedFile f(path);
  return decode_pc2(f.text(), path.string());
}

std::optional<std::vector<Index>> match_connectivity(std::span<const VertexId> ids_a,
                                                     std::span<const std::array<Index, 3>> triangles_a,
                                                     std::span<const VertexId> ids_b,
                                                     std::span<const std::array<Index, 3>> triangles_b) {
  if (ids_a.empty() != ids_b.empty() || ids_a.size() != ids_b.size() || triangles_a.size() != triangles_b.size())
    return std::nullopt;
  std::vector<Index> a_to_b;
  if (ids_a.empty()) {
    // Without ids only identical index triangles (in any order) count; the vertex count is implied by them.
    Index n = 0;
    for (const auto& t : triangles_a) n = std::max({n, t[0] + 1, t[1] + 1, t[2] + 1});
    a_to_b.resize(n);
    for (Index i = 0; i < n; ++i) a_to_b[i] = i;
  } else if (std::equal(ids_a.begin(), ids_a.end(), ids_b.begin())) {
    a_to_b.resize(ids_a.size());
    for (std::size_t i = 0; i < ids_a.size(); ++i) a_to_b[i] = Index(i);
  } else {
    std::unordered_map<VertexId, Index> in_b;
    in_b.reserve(ids_b.size());
    for (std::size_t i = 0; i < ids_b.size(); ++i) in_b.emplace(ids_b[i], Index(i));
    if (in_b.size() != ids_b.size()) return std::nullopt;  // repeated ids
    a_to_b.resize(ids_a.size());
    std::vector<std::uint8_t> used(ids_b.size(), 0);
    for (std::size_t i = 0; i < ids_a.size(); ++i) {
      const auto it = in_b.find(ids_a[i]);
      if (it == in_b.end() || used[it->second]) return std::nullopt;
      used[it->second] = 1;
      a_to_b[i] = it->second;
    }
  }
  // Canonical triangles: rotated so the smallest index comes first (orientation kept), then sorted.
  auto canon = [](std::array<Index, 3> t) {
    while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};
    return t;
  };
  std::vector<std::array<Index, 3>> ta, tb;
  ta.reserve(triangles_a.size());
  tb.reserve(triangles_b.size());
  for (const auto& t : triangles_a) {
    for (Index v : t)
      if (v >= a_to_b.size()) return std::nullopt;
    ta.push_back(canon({a_to_b[t[0]], a_to_b[t[1]], a_to_b[t[2]]}));
  }
  for (const auto& t : triangles_b) tb.push_back(canon(t));
  std::sort(ta.begin(), ta.end());
  std::sort(tb.begin(), tb.end());
  if (ta != tb) return std::nullopt;
  return a_to_b;
}

}  // namespace topotrack
