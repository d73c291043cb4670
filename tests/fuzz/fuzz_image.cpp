// Environment maps: Radiance .hdr (stb behind a header and run-length walk)
// and OpenEXR; the first byte picks the format.
#include <cstdint>

#include "fuzz_input.hpp"
#include "prt/environment.hpp"
#include "prt/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const auto file = prt::fuzz::input_file(data + 1, size - 1, data[0] % 2 ? ".exr" : ".hdr");
  try {
    prt::Environment::load(file);
  } catch (const prt::Error&) {
  }
  return 0;
}
