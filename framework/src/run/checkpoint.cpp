#include "prt/checkpoint.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "prt/error.hpp"
#include "prt/output_file.hpp"

namespace prt {
namespace fs = std::filesystem;

Digest& Digest::add(const void* data, std::size_t bytes) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < bytes; ++i) hash_ = (hash_ ^ p[i]) * 0x100000001b3ull;
  return *this;
}

Digest& Digest::add(const std::string& text) {
  const std::uint64_t size = text.size();
  add(&size, sizeof size);  // "ab" + "c" differs from "a" + "bc"
  return add(text.data(), text.size());
}

Digest& Digest::add_file(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw Error(file.string() + ": cannot read it");
  std::vector<char> buffer(1 << 20);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    add(buffer.data(), static_cast<std::size_t>(in.gcount()));
  }
  return *this;
}

std::string Digest::hex() const {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(hash_));
  return text;
}

namespace {

constexpr char kMagic[8] = {'P', 'R', 'T', 'C', 'K', 'P', 'T', '1'};
enum class Scalar : std::uint32_t { f32 = 0, f64 = 1, i32 = 2, text = 3 };

struct Header {
  char magic[8];
  std::uint32_t scalar;
  std::uint32_t reserved;
  std::uint64_t rows, cols, digest;
};

// Writes a whole file or nothing under its name: temporary, fsync, rename,
// fsync of the folder (so the rename survives a crash of the machine too).
void write_raw(const fs::path& file, const void* head, std::size_t head_bytes, const void* data,
               std::size_t bytes) {
  const fs::path temporary = file.string() + ".tmp-" + std::to_string(::getpid());
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw Error(io_failure(temporary, errno, "creating a checkpoint part"));
  const auto fail = [&](int error_number) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw Error(io_failure(file, error_number, "writing a checkpoint part"));
  };
  for (const auto& [from, size] : {std::pair{head, head_bytes}, {data, bytes}})
    if (const int failed = write_fully(fd, from, size)) {
      ::close(fd);
      fail(failed);
    }
  const int synced = ::fsync(fd) == 0 ? 0 : errno;
  const int closed = ::close(fd) == 0 ? 0 : errno;  // always closed, even when fsync failed
  if (synced || closed) fail(synced ? synced : closed);
  if (std::rename(temporary.c_str(), file.c_str()) != 0) fail(errno);
  sync_folder(file.parent_path());
}

void write_whole(const fs::path& file, const Header& header, const void* data, std::size_t bytes) {
  write_raw(file, &header, sizeof header, data, bytes);
}

Header header_for(Scalar scalar, std::uint64_t rows, std::uint64_t cols, const void* data,
                  std::size_t bytes) {
  Header header{};
  std::memcpy(header.magic, kMagic, sizeof kMagic);
  header.scalar = static_cast<std::uint32_t>(scalar);
  header.rows = rows, header.cols = cols;
  header.digest = Digest().add(data, bytes).value();
  return header;
}

// Reads a part, checking its magic, type, size and digest.
template <class T>
std::vector<T> read_whole(const fs::path& file, Scalar scalar, std::uint64_t& rows,
                          std::uint64_t& cols) {
  std::ifstream in(file, std::ios::binary);
  Header header{};
  if (!in.read(reinterpret_cast<char*>(&header), sizeof header) ||
      std::memcmp(header.magic, kMagic, sizeof kMagic) != 0 ||
      header.scalar != static_cast<std::uint32_t>(scalar))
    throw Error(file.string() + ": not a checkpoint part of the expected type");
  const std::uint64_t count = header.rows * header.cols;
  if (header.cols != 0 && count / header.cols != header.rows)
    throw Error(file.string() + ": damaged checkpoint part (size overflows)");
  const auto expected = static_cast<std::uintmax_t>(sizeof header + count * sizeof(T));
  if (fs::file_size(file) != expected)
    throw Error(file.string() + ": damaged checkpoint part (its size disagrees with its header)");
  std::vector<T> values(count);
  in.read(reinterpret_cast<char*>(values.data()), static_cast<std::streamsize>(count * sizeof(T)));
  if (!in || Digest().add(values.data(), count * sizeof(T)).value() != header.digest)
    throw Error(file.string() + ": damaged checkpoint part (its digest disagrees)");
  rows = header.rows, cols = header.cols;
  return values;
}

}  // namespace

fs::path CheckpointStore::folder_for(const fs::path& output) {
  const fs::path folder = output.parent_path().empty() ? fs::path(".") : output.parent_path();
  return folder / ("." + output.filename().string() + ".checkpoint");
}

namespace {

// An exclusive lock on the folder's "lock" file (created with the folder):
// the descriptor, or throws when another process holds it.
int lock_folder(const fs::path& folder) {
  std::error_code error;
  fs::create_directories(folder, error);
  if (error) throw Error(io_failure(folder, error.value(), "creating the checkpoint folder"));
  const fs::path file = folder / "lock";
  const int fd = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw Error(file.string() + ": cannot open: " + std::strerror(errno));
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd);
    throw Error(folder.string() +
                ": another prt process is using this checkpoint; wait for it or stop it");
  }
  return fd;
}

}  // namespace

void CheckpointStore::discard(const fs::path& output) {
  const fs::path folder = folder_for(output);
  if (!fs::exists(folder)) return;
  const int fd = lock_folder(folder);
  std::error_code ignored;
  fs::remove_all(folder, ignored);
  ::close(fd);
}

CheckpointStore::~CheckpointStore() {
  if (lock_ >= 0) ::close(lock_);
}

CheckpointStore::CheckpointStore(const fs::path& output, const std::string& key,
                                 const std::string& description, bool exclusive)
    : folder_(folder_for(output)) {
  if (exclusive) lock_ = lock_folder(folder_);
  try {
    open_key(key, description);
  } catch (...) {
    if (lock_ >= 0) ::close(lock_), lock_ = -1;
    throw;
  }
}

void CheckpointStore::open_key(const std::string& key, const std::string& description) {
  const fs::path key_file = folder_ / "key";
  std::string stored;
  if (fs::exists(key_file)) {
    std::ifstream in(key_file);
    std::getline(in, stored);
  }
  if (!stored.empty()) {  // an empty key (never completed) counts as none
    if (stored != key) {
      if (lock_ >= 0) ::close(lock_), lock_ = -1;
      throw Error(folder_.string() +
                  ": a checkpoint of a different run (the scene, mesh or plug-ins changed since "
                  "it was written); delete the folder or rerun with --restart");
    }
    return;
  }
  fs::create_directories(folder_);
  const std::string text = key + "\n" + description + "\n";
  write_raw(key_file, text.data(), text.size(), nullptr, 0);
}

bool CheckpointStore::has(const std::string& name) const {
  return fs::exists(folder_ / name);
}

bool CheckpointStore::claim(const std::string& name) const {
  const fs::path file = folder_ / name;
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    if (errno == EEXIST) return false;
    throw Error(file.string() + ": cannot create: " + std::strerror(errno));
  }
  ::close(fd);
  return true;
}

void CheckpointStore::save(const std::string& name, const MatrixXfRow& m) const {
  const std::size_t bytes = static_cast<std::size_t>(m.size()) * sizeof(float);
  write_whole(folder_ / name, header_for(Scalar::f32, m.rows(), m.cols(), m.data(), bytes),
              m.data(), bytes);
}

void CheckpointStore::save(const std::string& name, const Eigen::MatrixXd& m) const {
  const std::size_t bytes = static_cast<std::size_t>(m.size()) * sizeof(double);
  write_whole(folder_ / name, header_for(Scalar::f64, m.rows(), m.cols(), m.data(), bytes),
              m.data(), bytes);
}

void CheckpointStore::save(const std::string& name, const std::vector<std::int32_t>& v) const {
  const std::size_t bytes = v.size() * sizeof(std::int32_t);
  write_whole(folder_ / name, header_for(Scalar::i32, v.size(), 1, v.data(), bytes), v.data(),
              bytes);
}

void CheckpointStore::save_text(const std::string& name, const std::string& text) const {
  write_whole(folder_ / name, header_for(Scalar::text, text.size(), 1, text.data(), text.size()),
              text.data(), text.size());
}

std::string CheckpointStore::load_text(const std::string& name) const {
  std::uint64_t rows = 0, cols = 0;
  const auto chars = read_whole<char>(folder_ / name, Scalar::text, rows, cols);
  return std::string(chars.begin(), chars.end());
}

void CheckpointStore::remove_part(const std::string& name) const {
  std::error_code ignored;
  fs::remove(folder_ / name, ignored);
}

void CheckpointStore::remove_temporaries() const {
  std::error_code ignored;
  for (const auto& entry : fs::directory_iterator(folder_, ignored))
    if (entry.path().filename().string().find(".tmp-") != std::string::npos)
      fs::remove(entry.path(), ignored);
}

MatrixXfRow CheckpointStore::load_floats(const std::string& name) const {
  std::uint64_t rows = 0, cols = 0;
  const auto values = read_whole<float>(folder_ / name, Scalar::f32, rows, cols);
  return Eigen::Map<const MatrixXfRow>(values.data(), static_cast<Eigen::Index>(rows),
                                       static_cast<Eigen::Index>(cols));
}

Eigen::MatrixXd CheckpointStore::load_doubles(const std::string& name) const {
  std::uint64_t rows = 0, cols = 0;
  const auto values = read_whole<double>(folder_ / name, Scalar::f64, rows, cols);
  return Eigen::Map<const Eigen::MatrixXd>(values.data(), static_cast<Eigen::Index>(rows),
                                           static_cast<Eigen::Index>(cols));
}

std::vector<std::int32_t> CheckpointStore::load_ints(const std::string& name) const {
  std::uint64_t rows = 0, cols = 0;
  return read_whole<std::int32_t>(folder_ / name, Scalar::i32, rows, cols);
}

std::vector<std::string> CheckpointStore::parts() const {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder_)) {
    const std::string name = entry.path().filename().string();
    if (name != "key" && name != "lock" && name.rfind("claim-", 0) != 0 &&
        name.find(".tmp-") == std::string::npos)
      names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

void CheckpointStore::remove() const {
  std::error_code ignored;
  fs::remove_all(folder_, ignored);
}

}  // namespace prt
