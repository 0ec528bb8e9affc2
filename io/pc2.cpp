#include "io/pc2.hpp"

#include <bit>
#include <cstring>

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

void Pc2Writer::add_sample(std::span<const std::array<double, 3>> positions) {
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

}  // namespace topotrack
