#pragma once
//! Atomic file writes: readers of the target see either the old file or the complete new one.
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

namespace topotrack {

//! Streams bytes into a temporary file next to `target` (same directory, so rename is atomic);
//! commit() flushes, fsyncs, and renames it over the target. Destroyed without commit (an error or
//! an exception in the producer) it removes the temporary file and leaves the target untouched.
class AtomicFileWriter {
public:
  //! \throw IoError naming the target when the temporary file cannot be created.
  explicit AtomicFileWriter(std::filesystem::path target);
  ~AtomicFileWriter();
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;

  //! Append bytes (buffered). \throw IoError naming the target; the temporary file is removed.
  void write(std::string_view bytes);
  //! Flush, fsync, close and rename over the target. \throw IoError naming the target.
  void commit();

  const std::filesystem::path& target() const { return target_; }
  const std::filesystem::path& temp_path() const { return temp_; }

private:
  void flush_buffer();
  [[noreturn]] void fail(const char* what, int err);
  void discard() noexcept;

  std::filesystem::path target_;
  std::filesystem::path temp_;
  int fd_ = -1;
  std::string buffer_;
  bool committed_ = false;
};

//! Write `bytes` to `path` atomically. \throw IoError naming the path.
void write_file_atomic(const std::filesystem::path& path, std::string_view bytes);

//! Streaming variant: `produce` writes into the writer; commit happens after it returns. If it
//! throws, the temporary file is removed, the target is untouched and the exception propagates.
void write_file_atomic(const std::filesystem::path& path, const std::function<void(AtomicFileWriter&)>& produce);

}  // namespace topotrack
