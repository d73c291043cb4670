// The plug-in scanner's ELF reader (dynamic symbols and the info record).
#include <cstdint>

#include "../../framework/src/elf_symbols.hpp"
#include "fuzz_input.hpp"
#include "prt/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = prt::fuzz::input_file(data, size, ".so");
  try {
    prt::elf::dynamic_symbols(file);
    prt::elf::symbol_bytes(file, "prt_plugin_info");
  } catch (const prt::Error&) {
  }
  return 0;
}
