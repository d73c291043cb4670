// The mesh readers: the first byte picks the format, the rest is the file.
#include <cstdint>

#include "fuzz_input.hpp"
#include "prt/error.hpp"
#include "prt/mesh.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* extensions[] = {".off", ".ply", ".stl", ".obj"};
  const auto file = prt::fuzz::input_file(data + 1, size - 1, extensions[data[0] % 4]);
  try {
    prt::load_mesh(file);
  } catch (const prt::Error&) {
  }
  return 0;
}
