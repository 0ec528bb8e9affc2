#pragma once
//! Export for hosts that demand a fixed vertex count: stretches of frames with constant connectivity become a
//! base mesh plus a PC2 point cache (Blender's Mesh Cache modifier, 3ds Max, Maya read it).
//!
//! Bytes <-> flat arrays only (positions as MeshData holds them).
//!
//! PC2 layout (little endian): char[12] "POINTCACHE2\0", int32 version = 1, int32 number of points,
//! float32 start frame, float32 sample rate, int32 number of samples, then per sample per point float32 x y z.
#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>


namespace topotrack {

class AtomicFileWriter;

struct Pc2Header {
  std::int32_t points = 0;
  float start_frame = 0;
  float sample_rate = 1;  //!< frames between samples
  std::int32_t samples = 0;
};
inline constexpr std::size_t kPc2HeaderBytes = 32;

//! Streams a PC2 file sample by sample to a temporary file; commit() renames it over the target.
class Pc2Writer {
public:
  //! \throw InvalidInput for points < 1 or samples < 1; IoError when the file cannot be created.
  Pc2Writer(const std::filesystem::path& path, const Pc2Header& header);
  ~Pc2Writer();
  Pc2Writer(const Pc2Writer&) = delete;
  Pc2Writer& operator=(const Pc2Writer&) = delete;
  //! Append one sample. \throw InvalidInput on a wrong point count or one sample too many; IoError.
  void add_sample(std::span<const std::array<double, 3>> positions);
  //! \throw InvalidInput when fewer samples than announced were added; IoError.
  void commit();

private:
  std::unique_ptr<AtomicFileWriter> out_;
  Pc2Header header_;
  std::int32_t written_ = 0;
  std::vector<float> buffer_;
};

struct Pc2Data {
  Pc2Header header;
  std::vector<float> xyz;  //!< samples * points * 3
  std::span<const float> sample(std::size_t s) const {
    return {xyz.data() + s * 3 * std::size_t(header.points), 3 * std::size_t(header.points)};
  }
};
//! \throw InvalidInput "<name>: <fault>" on a bad magic, version, negative counts or a size that disagrees.
Pc2Data decode_pc2(std::string_view bytes, const std::string& name);
//! \throw IoError when unreadable; InvalidInput as decode_pc2, naming the path.
Pc2Data read_pc2(const std::filesystem::path& path);

}  // namespace topotrack
