// The bake reader. By default inputs meet the PRT-BAKE header's length and
// checksum check, as a damaged file would. With PRT_FUZZ_SEAL=1 each input
// is sealed first (a valid checksum, as a deliberately crafted file would
// have), so libhdf5 and the value checks behind it are reached.
#include <cstdint>
#include <cstdlib>

#include "../../framework/src/bake_userblock.hpp"
#include "fuzz_input.hpp"
#include "prt/bake_file.hpp"
#include "prt/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool seal = std::getenv("PRT_FUZZ_SEAL") != nullptr;
  const auto file = prt::fuzz::input_file(data, size, ".h5");
  try {
    if (seal && size >= prt::kBakeUserBlockSize) prt::seal_bake_file(file, prt::kBakeFormatVersion);
    prt::read_bake(file);
  } catch (const prt::Error&) {
  }
  return 0;
}
