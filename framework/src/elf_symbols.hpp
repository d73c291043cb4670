// Reads exported symbols of an ELF shared library from the file, without
// loading it: the registry uses this to read info records of plug-ins it may
// never load. (Boost.DLL's library_info lists symbol names but not contents.)
#pragma once
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace prt::elf {

struct SymbolTable {
  std::vector<std::string> names;  // defined dynamic symbols
  bool has(const std::string& name) const;
};

// Throws prt::Error if the file is not a 64-bit little-endian ELF object.
SymbolTable dynamic_symbols(const std::filesystem::path& file);

// The bytes of a defined data symbol as stored in the file, or nullopt when the
// symbol is absent or has no file contents.
std::optional<std::vector<char>> symbol_bytes(const std::filesystem::path& file,
                                              const std::string& name);

}  // namespace prt::elf
