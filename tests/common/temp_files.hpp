// Files for tests that write to disk: a fresh folder under the temporary
// directory, whole files written and read back.
#pragma once
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace prt::test {

// `<tmp>/<prefix><name>`, emptied and created (mode 0755, so the plug-in
// scanner's checks hold whatever the umask).
inline std::filesystem::path fresh_dir(const std::string& prefix, const std::string& name) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / (prefix + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::permissions(dir, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                           fs::perms::others_read | fs::perms::others_exec);
  return dir;
}

inline void write_file(const std::filesystem::path& file, const std::string& bytes) {
  std::ofstream(file, std::ios::binary) << bytes;
}

inline std::string read_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace prt::test
