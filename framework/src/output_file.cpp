#include "prt/output_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <mutex>
#include <string_view>

#include "bake_userblock.hpp"
#include "prt/error.hpp"

namespace prt {
namespace fs = std::filesystem;

const char* to_string(FileKind kind) {
  switch (kind) {
    case FileKind::missing:
      return "nothing";
    case FileKind::bake:
      return "a bake file";
    case FileKind::png:
      return "a PNG image";
    case FileKind::exr:
      return "an OpenEXR image";
    case FileKind::scene:
      return "a scene file";
    case FileKind::text:
      return "a text file";
    case FileKind::json:
      return "a JSON file";
    case FileKind::csv:
      return "a CSV table";
    case FileKind::other:
      return "a file of another kind";
  }
  return "?";
}

FileKind detect_file_kind(const fs::path& file) {
  std::error_code error;
  if (!fs::exists(file, error)) return FileKind::missing;
  std::ifstream in(file, std::ios::binary);
  char head[512] = {};
  in.read(head, sizeof head);
  const std::size_t n = static_cast<std::size_t>(in.gcount());
  if (n == 0) return FileKind::other;  // empty: nothing to lose, any kind may replace it
  if (n >= sizeof kBakeMagic - 1 && std::memcmp(head, kBakeMagic, sizeof kBakeMagic - 1) == 0)
    return FileKind::bake;
  static const unsigned char png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (n >= 8 && std::memcmp(head, png, 8) == 0) return FileKind::png;
  static const unsigned char exr[4] = {0x76, 0x2f, 0x31, 0x01};
  if (n >= 4 && std::memcmp(head, exr, 4) == 0) return FileKind::exr;
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(head[i]);
    if (c == 0 || (c < 32 && c != '\n' && c != '\r' && c != '\t')) return FileKind::other;
  }
  if (file.extension() == ".toml") return FileKind::scene;
  const std::size_t first = std::string_view(head, n).find_first_not_of(" \t\r\n");
  if (first != std::string_view::npos && (head[first] == '{' || head[first] == '['))
    return FileKind::json;
  if (file.extension() == ".csv") return FileKind::csv;
  return FileKind::text;
}

FileKind report_kind(const fs::path& file) {
  if (file.extension() == ".json") return FileKind::json;
  if (file.extension() == ".csv") return FileKind::csv;
  return FileKind::text;
}

namespace {

std::string file_type_name(const struct stat& s) {
  if (S_ISDIR(s.st_mode)) return "a directory";
  if (S_ISCHR(s.st_mode)) return "a character device";
  if (S_ISBLK(s.st_mode)) return "a block device";
  if (S_ISFIFO(s.st_mode)) return "a FIFO";
  if (S_ISSOCK(s.st_mode)) return "a socket";
  return "not a regular file";
}

bool same_file(const fs::path& a, const fs::path& b) {
  struct stat sa {
  }, sb{};
  return stat(a.c_str(), &sa) == 0 && stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev &&
         sa.st_ino == sb.st_ino;
}

}  // namespace

void check_output(const OutputRequest& output, const std::vector<fs::path>& inputs, bool force) {
  const std::string where = output.path.string() + ": ";
  if (output.path.empty() || output.path.filename().empty() || output.path.filename() == "." ||
      output.path.filename() == "..")
    throw Error(where + "the " + output.role + " must name a file");
  struct stat s {};
  if (stat(output.path.c_str(), &s) == 0) {
    if (!S_ISREG(s.st_mode))
      throw Error(where + "refusing to write the " + output.role + " over " + file_type_name(s) +
                  "; name a regular file");
  } else if (errno != ENOENT) {
    throw Error(where + "cannot write the " + output.role + ": " + std::strerror(errno));
  }
  const fs::path folder =
      output.path.parent_path().empty() ? fs::path(".") : output.path.parent_path();
  struct stat f {};
  if (stat(folder.c_str(), &f) != 0) {
    if (!output.create_folder)
      throw Error(where + "the folder " + folder.string() + " of the " + output.role +
                  " does not exist");
  } else if (!S_ISDIR(f.st_mode)) {
    throw Error(where + folder.string() + " is not a directory");
  }
  for (const auto& input : inputs)
    if (!input.empty() && same_file(output.path, input))
      throw Error(where + "the " + output.role + " is the same file as the input " +
                  input.string() + "; choose another output path");
  const FileKind existing = detect_file_kind(output.path);
  const bool replaceable = existing == FileKind::missing || existing == output.kind ||
                           (existing == FileKind::other && s.st_size == 0);
  if (!replaceable && !force)
    throw Error(where + "refusing to replace " + to_string(existing) + " with " +
                to_string(output.kind) + " (the " + output.role + "); use " + output.force_option +
                " to overwrite it");
}

// ---- temporaries, removed on SIGINT/SIGTERM ------------------------------

namespace {

// Fixed storage the signal handler can read without allocating.
// A slot's state: 0 free, 1 being filled, 2 holds a temporary's path.
constexpr std::size_t kMaxTemporaries = 16, kMaxPath = 4096;
struct TemporarySlot {
  std::atomic<int> state{0};
  char path[kMaxPath] = {};
};
std::array<TemporarySlot, kMaxTemporaries> temporaries;
struct sigaction previous_int {
}, previous_term{};
std::mutex handlers_mutex;
int active_registrations = 0;

void remove_temporaries_and_reraise(int signal_number) {
  for (auto& slot : temporaries)
    if (slot.state.load() == 2) unlink(slot.path);
  sigaction(signal_number, signal_number == SIGINT ? &previous_int : &previous_term, nullptr);
  raise(signal_number);
}

// The handlers are in place only while a temporary exists, and the ones they
// replaced are restored afterwards.
void install_handlers() {
  std::lock_guard lock(handlers_mutex);
  if (active_registrations++ > 0) return;
  struct sigaction action {};
  action.sa_handler = remove_temporaries_and_reraise;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, &previous_int);
  sigaction(SIGTERM, &action, &previous_term);
}

void restore_handlers() {
  std::lock_guard lock(handlers_mutex);
  if (--active_registrations > 0) return;
  sigaction(SIGINT, &previous_int, nullptr);
  sigaction(SIGTERM, &previous_term, nullptr);
}

// Holds a temporary's path in a slot while it may exist. The path is held
// before the file is created, so a signal between the two removes it too.
class TemporaryRegistration {
 public:
  TemporaryRegistration() { install_handlers(); }
  ~TemporaryRegistration() {
    if (slot_) slot_->state.store(0);
    restore_handlers();
  }
  TemporaryRegistration(const TemporaryRegistration&) = delete;
  TemporaryRegistration& operator=(const TemporaryRegistration&) = delete;

  void hold(const fs::path& path) {
    const std::string text = path.string();
    if (text.size() >= kMaxPath) return;
    if (!slot_) slot_ = claim_slot();
    if (!slot_) return;
    slot_->state.store(1);  // the handler skips a slot while its path is rewritten
    std::memcpy(slot_->path, text.c_str(), text.size() + 1);
    slot_->state.store(2);
  }
  // The held name turned out to be another file's (EEXIST): not ours to remove.
  void drop() {
    if (slot_) slot_->state.store(1);
  }

 private:
  static TemporarySlot* claim_slot() {
    for (auto& s : temporaries) {
      int expected = 0;
      if (s.state.compare_exchange_strong(expected, 1)) return &s;
    }
    return nullptr;
  }
  TemporarySlot* slot_ = nullptr;
};

// ".NAME.tmp-PID-N": the PID of a process that no longer exists marks it stale.
void remove_stale_temporaries(const fs::path& folder, const std::string& name) {
  const std::string prefix = "." + name + ".tmp-";
  std::error_code error;
  for (fs::directory_iterator it(folder, error), end; !error && it != end; it.increment(error)) {
    const std::string entry = it->path().filename().string();
    if (entry.rfind(prefix, 0) != 0) continue;
    const std::string rest = entry.substr(prefix.size());
    const auto dash = rest.find('-');
    if (dash == 0 || dash == std::string::npos ||
        rest.find_first_not_of("0123456789-") != std::string::npos)
      continue;
    const long pid = std::strtol(rest.substr(0, dash).c_str(), nullptr, 10);
    if (pid <= 0 || pid == getpid()) continue;
    if (kill(static_cast<pid_t>(pid), 0) == -1 && errno == ESRCH) {
      std::error_code ignored;
      fs::remove(it->path(), ignored);
    }
  }
}

// Starts at a value of this process's own (its start time and an address),
// so that a process of the same PID in another PID namespace sharing the
// folder, or a stale file of an earlier one, is unlikely to hold the name
// that is registered for removal before it is created.
unsigned first_temporary_number() {
  const auto now = std::chrono::steady_clock::now().time_since_epoch().count();
  const auto here = reinterpret_cast<std::uintptr_t>(&now);
  return static_cast<unsigned>((std::uint64_t(now) ^ (std::uint64_t(here) << 17)) % 1000000000u);
}
std::atomic<unsigned> temporary_counter{first_temporary_number()};

}  // namespace

void write_atomically(const fs::path& file, const std::function<void(const fs::path&)>& write) {
  const fs::path folder = file.parent_path();
  if (!folder.empty()) {
    std::error_code error;
    fs::create_directories(folder, error);
    if (error) throw Error(io_failure(folder, error.value(), "creating the output's folder"));
  }
  const fs::path dir = folder.empty() ? fs::path(".") : folder;
  remove_stale_temporaries(dir, file.filename().string());
  fs::path temporary;
  int descriptor = -1;
  TemporaryRegistration registration;
  for (int attempt = 0; attempt < 100 && descriptor < 0; ++attempt) {
    // Built by appends: GCC 12 warns falsely (-Wrestrict) on "." + std::string.
    std::string name = ".";
    name.append(file.filename().string())
        .append(".tmp-")
        .append(std::to_string(getpid()))
        .append("-")
        .append(std::to_string(temporary_counter++));
    temporary = folder / name;
    registration.hold(temporary);
    descriptor = open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (descriptor < 0) registration.drop();
    if (descriptor < 0 && errno != EEXIST)
      throw Error(file.string() +
                  ": cannot create a temporary file beside it: " + std::strerror(errno));
  }
  if (descriptor < 0) throw Error(file.string() + ": cannot create a unique temporary file");
  close(descriptor);
  try {
    write(temporary);
    // Deferred write errors (a full disk on a file system that allocates
    // late) surface at fsync: the target is replaced only by what is on disk.
    flush_to_device(temporary, file);
    if (std::rename(temporary.c_str(), file.c_str()) != 0)
      throw Error(io_failure(file, errno, "renaming the finished temporary over it"));
  } catch (...) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw;
  }
  sync_folder(dir);
}

void write_text_file(const fs::path& file, const std::string& text) {
  write_atomically(file, [&](const fs::path& temporary) {
    write_bytes_checked(temporary, text.data(), text.size(), file);
  });
}

std::string io_failure(const fs::path& file, int error_number, const char* doing) {
  std::string reason = std::strerror(error_number);
  if (!reason.empty())
    reason[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(reason[0])));
  return file.string() + ": " + reason + " while " + doing;
}

int write_fully(int descriptor, const void* bytes, std::size_t size) {
  const char* from = static_cast<const char*>(bytes);
  while (size > 0) {
    const ssize_t wrote = ::write(descriptor, from, size);
    if (wrote < 0 && errno == EINTR) continue;
    if (wrote <= 0) return wrote < 0 ? errno : ENOSPC;
    from += wrote;
    size -= static_cast<std::size_t>(wrote);
  }
  return 0;
}

void sync_folder(const fs::path& folder) {
  const int descriptor = open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (descriptor >= 0) fsync(descriptor), close(descriptor);
}

void write_bytes_checked(const fs::path& path, const void* bytes, std::size_t size,
                         const fs::path& shown) {
  const fs::path& name = shown.empty() ? path : shown;
  const int descriptor = open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (descriptor < 0) throw Error(io_failure(name, errno, "creating it"));
  if (const int failed = write_fully(descriptor, bytes, size)) {
    close(descriptor);
    throw Error(io_failure(name, failed, "writing"));
  }
  const int synced = fsync(descriptor) == 0 ? 0 : errno;
  const int closed = close(descriptor) == 0 ? 0 : errno;
  if (synced || closed) throw Error(io_failure(name, synced ? synced : closed, "writing"));
}

void flush_to_device(const fs::path& path, const fs::path& shown) {
  const fs::path& name = shown.empty() ? path : shown;
  const int descriptor = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (descriptor < 0) throw Error(io_failure(name, errno, "reopening it to flush it"));
  const int synced = fsync(descriptor) == 0 ? 0 : errno;
  const int closed = close(descriptor) == 0 ? 0 : errno;
  if (synced || closed) throw Error(io_failure(name, synced ? synced : closed, "writing"));
}

}  // namespace prt
