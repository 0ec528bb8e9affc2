#pragma once
//! Read-only memory-mapped file: the readers parse straight from the page cache, no copy.
#include <cstddef>
#include <filesystem>
#include <span>
#include <string_view>

namespace topotrack {

//! A whole file mapped read-only (RAII, move-only). A 0-byte file is not mapped and gives an empty span.
class MappedFile {
public:
  //! Map `path`. \throw IoError naming the path and the errno text (missing, unreadable, not a regular file).
  explicit MappedFile(const std::filesystem::path& path);
  ~MappedFile();
  MappedFile(MappedFile&& other) noexcept;
  MappedFile& operator=(MappedFile&& other) noexcept;
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  const char* data() const { return static_cast<const char*>(data_); }
  std::span<const std::byte> bytes() const { return {static_cast<const std::byte*>(data_), size_}; }
  std::string_view text() const { return {data(), size_}; }

private:
  void release() noexcept;

  std::filesystem::path path_;
  const void* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace topotrack
