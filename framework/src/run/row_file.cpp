#include "prt/row_file.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "prt/error.hpp"

namespace prt {

namespace {

std::string os_error() {
  return std::strerror(errno);
}

std::size_t page_size() {
  return static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
}

}  // namespace

std::shared_ptr<RowFile> RowFile::create(const std::filesystem::path& folder, Eigen::Index rows,
                                         Eigen::Index cols) {
  // A free name: ranks on other nodes may share this process's id.
  std::filesystem::path name;
  int fd = -1;
  for (int attempt = 0; fd < 0 && attempt < 1000; ++attempt) {
    name = folder /
           (".transfer-rows.tmp-" + std::to_string(::getpid()) + "-" + std::to_string(attempt));
    fd = ::open(name.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd < 0 && errno != EEXIST) break;
  }
  if (fd < 0)
    throw Error(name.string() + ": cannot create the file for the transfer's rows: " + os_error());
  ::unlink(name.c_str());  // unnamed from here: gone with the process, however it ends
  std::shared_ptr<RowFile> file(new RowFile(fd, rows, cols, folder));
  // Reserve the blocks now, so a full disk is a message here, not SIGBUS later.
  if (file->bytes_ > 0) {
    const int error = ::posix_fallocate(fd, 0, static_cast<off_t>(file->bytes_));
    if (error != 0)
      throw Error(folder.string() + ": no room for the transfer's rows (" +
                  std::to_string(file->bytes_ / 1000000) +
                  " MB) kept on disk beyond the memory budget: " + std::strerror(error));
  }
  return file;
}

RowFile::RowFile(int fd, Eigen::Index rows, Eigen::Index cols, std::filesystem::path where)
    : fd_(fd),
      rows_(rows),
      cols_(cols),
      where_(std::move(where)),
      bytes_(static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols) * sizeof(float)) {}

RowFile::~RowFile() {
  if (mapping_) ::munmap(mapping_, bytes_);
  if (fd_ >= 0) ::close(fd_);
}

void RowFile::write(Eigen::Index first, Eigen::Ref<const MatrixXfRow> block) {
  if (mapping_) throw Error("RowFile::write after map()");
  if (block.cols() != cols_ || first < 0 || first + block.rows() > rows_)
    throw Error("RowFile::write: rows [" + std::to_string(first) + ", " +
                std::to_string(first + block.rows()) + ") x " + std::to_string(block.cols()) +
                " outside the " + std::to_string(rows_) + " x " + std::to_string(cols_) + " file");
  if (block.rows() > 1 && block.outerStride() != block.cols())
    return write(first, MatrixXfRow(block));  // rows with gaps: one contiguous copy
  const char* data = reinterpret_cast<const char*>(block.data());
  std::size_t left = static_cast<std::size_t>(block.size()) * sizeof(float);
  off_t at = static_cast<off_t>(first) * static_cast<off_t>(cols_) * off_t(sizeof(float));
  while (left > 0) {
    const ssize_t wrote = ::pwrite(fd_, data, left, at);
    if (wrote < 0 && errno == EINTR) continue;
    if (wrote <= 0)
      throw Error(where_.string() + ": writing the transfer's rows failed: " + os_error());
    data += wrote;
    at += wrote;
    left -= static_cast<std::size_t>(wrote);
  }
}

void RowFile::map() {
  if (mapping_ || bytes_ == 0) return;
  void* p = ::mmap(nullptr, bytes_, PROT_READ, MAP_SHARED, fd_, 0);
  if (p == MAP_FAILED)
    throw Error(where_.string() + ": cannot map the transfer's rows: " + os_error());
  mapping_ = p;
}

Eigen::Map<const MatrixXfRow> RowFile::matrix() const {
  if (!mapping_ && bytes_ > 0) throw Error("RowFile::matrix before map()");
  return {static_cast<const float*>(mapping_), rows_, cols_};
}

void RowFile::release(Eigen::Index first, Eigen::Index last) const {
  if (!mapping_ || last <= first) return;
  // Every page the rows touch, shared ones too: the mapping is read-only and
  // backed by the file, so a dropped page costs a neighbour still reading it
  // a minor fault from the page cache, never data.
  const std::size_t page = page_size(), row = static_cast<std::size_t>(cols_) * sizeof(float);
  const std::size_t begin = static_cast<std::size_t>(first) * row / page * page;
  const std::size_t end =
      (std::min(bytes_, static_cast<std::size_t>(last) * row) + page - 1) / page * page;
  if (end > begin) ::madvise(static_cast<char*>(mapping_) + begin, end - begin, MADV_DONTNEED);
}

}  // namespace prt
