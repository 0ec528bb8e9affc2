#include "io/mapped_file.hpp"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <utility>

#include "io/error.hpp"

namespace topotrack {

namespace {
// Closes the descriptor on every path out of the constructor; the mapping outlives it.
struct FdGuard {
  int fd;
  ~FdGuard() {
    if (fd >= 0) ::close(fd);
  }
};
}  // namespace

MappedFile::MappedFile(const std::filesystem::path& path) : path_(path) {
  // O_NONBLOCK: opening a FIFO must not wait for a writer; the S_ISREG check below rejects it.
  FdGuard guard{::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK)};
  if (guard.fd < 0) TT_THROW(IoError, path.string() << ": cannot open: " << std::strerror(errno));
  struct stat st {};
  if (::fstat(guard.fd, &st) != 0)
    TT_THROW(IoError, path.string() << ": cannot stat: " << std::strerror(errno));
  if (!S_ISREG(st.st_mode))
    TT_THROW(IoError, path.string() << ": cannot map: "
                                    << std::strerror(S_ISDIR(st.st_mode) ? EISDIR : EINVAL));
  size_ = static_cast<std::size_t>(st.st_size);
  if (size_ == 0) return;
  void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE | MAP_POPULATE, guard.fd, 0);
  if (p == MAP_FAILED) {
    size_ = 0;
    TT_THROW(IoError, path.string() << ": cannot map: " << std::strerror(errno));
  }
  ::madvise(p, size_, MADV_SEQUENTIAL);
  data_ = p;
}

MappedFile::~MappedFile() { release(); }

MappedFile::MappedFile(MappedFile&& other) noexcept
    : path_(std::move(other.path_)),
      data_(std::exchange(other.data_, nullptr)),
      size_(std::exchange(other.size_, 0)) {}

MappedFile& MappedFile::operator=(MappedFile&& other) noexcept {
  if (this != &other) {
    release();
    path_ = std::move(other.path_);
    data_ = std::exchange(other.data_, nullptr);
    size_ = std::exchange(other.size_, 0);
  }
  return *this;
}

void MappedFile::release() noexcept {
  if (data_) ::munmap(const_cast<void*>(data_), size_);
  data_ = nullptr;
  size_ = 0;
}

}  // namespace topotrack
