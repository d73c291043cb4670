// Shared by the fuzz harnesses: the readers under test take file paths, so
// each input is written to a private temporary file first.
#pragma once
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

namespace prt::fuzz {

inline std::filesystem::path input_file(const std::uint8_t* data, std::size_t size,
                                        const std::string& extension) {
  static const std::filesystem::path dir = [] {
    const auto d =
        std::filesystem::temp_directory_path() / ("prt-fuzz-" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  const auto file = dir / ("input" + extension);
  if (FILE* f = std::fopen(file.c_str(), "wb")) {
    std::fwrite(data, 1, size, f);
    std::fclose(f);
  }
  return file;
}

}  // namespace prt::fuzz
