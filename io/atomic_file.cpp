#include "io/atomic_file.hpp"

#include <atomic>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <unistd.h>

#include "io/error.hpp"

namespace topotrack {

namespace {

constexpr std::size_t kBufferBytes = 1 << 20;
std::atomic<unsigned> g_temp_counter{0};

std::filesystem::path temp_name(const std::filesystem::path& target) {
  // Appended piecewise: GCC 12 warns falsely (-Wrestrict) on "literal" + std::string chains.
  std::string name = ".";
  name.append(target.filename().string()).append(".tmp-").append(std::to_string(::getpid()));
  name.append("-").append(std::to_string(g_temp_counter.fetch_add(1)));
  return target.parent_path() / name;
}

}  // namespace

AtomicFileWriter::AtomicFileWriter(std::filesystem::path target) : target_(std::move(target)) {
  if (target_.filename().empty()) TT_THROW(IoError, target_.string() << ": cannot write: not a file name");
  for (int attempt = 0; attempt < 100 && fd_ < 0; ++attempt) {
    temp_ = temp_name(target_);
    fd_ = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd_ < 0 && errno != EEXIST) break;
  }
  if (fd_ < 0) {
    const int err = errno;
    temp_.clear();
    TT_THROW(IoError, target_.string() << ": cannot create temporary file: " << std::strerror(err));
  }
  buffer_.reserve(kBufferBytes);
}

AtomicFileWriter::~AtomicFileWriter() {
  if (!committed_) discard();
}

void AtomicFileWriter::discard() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!temp_.empty()) ::unlink(temp_.c_str());
  temp_.clear();
}

void AtomicFileWriter::fail(const char* what, int err) {
  discard();
  TT_THROW(IoError, target_.string() << ": " << what << ": " << std::strerror(err));
}

void AtomicFileWriter::write(std::string_view bytes) {
  if (fd_ < 0) TT_THROW(IoError, target_.string() << ": write after commit or failure");
  if (buffer_.size() + bytes.size() > kBufferBytes) flush_buffer();
  if (bytes.size() >= kBufferBytes) {
    buffer_.assign(bytes);
    flush_buffer();
  } else {
    buffer_.append(bytes);
  }
}

void AtomicFileWriter::flush_buffer() {
  const char* p = buffer_.data();
  std::size_t left = buffer_.size();
  while (left > 0) {
    const ssize_t n = ::write(fd_, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("cannot write", errno);
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  buffer_.clear();
}

void AtomicFileWriter::commit() {
  if (fd_ < 0) TT_THROW(IoError, target_.string() << ": commit after commit or failure");
  flush_buffer();
  if (::fsync(fd_) != 0) fail("cannot fsync", errno);
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) fail("cannot close", errno);
  if (::rename(temp_.c_str(), target_.c_str()) != 0) fail("cannot rename temporary file over it", errno);
  committed_ = true;
  // Make the rename itself durable; a failure here cannot undo the write, so it is not an error.
  const std::filesystem::path dir = target_.parent_path().empty() ? "." : target_.parent_path();
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

void write_file_atomic(const std::filesystem::path& path, std::string_view bytes) {
  AtomicFileWriter w(path);
  w.write(bytes);
  w.commit();
}

void write_file_atomic(const std::filesystem::path& path, const std::function<void(AtomicFileWriter&)>& produce) {
  AtomicFileWriter w(path);
  produce(w);
  w.commit();
}

}  // namespace topotrack
