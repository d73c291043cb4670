#include "elf_symbols.hpp"

#include <elf.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <iterator>

#include "prt/error.hpp"

namespace prt::elf {
namespace {

struct ElfImage {
  std::vector<char> bytes;
  const Elf64_Ehdr* header = nullptr;

  template <class T>
  const T* at(std::uint64_t offset, std::uint64_t count = 1) const {
    if (offset > bytes.size() || count * sizeof(T) > bytes.size() - offset) return nullptr;
    return reinterpret_cast<const T*>(bytes.data() + offset);
  }
  const Elf64_Shdr* section(std::size_t i) const {
    return at<Elf64_Shdr>(header->e_shoff + i * sizeof(Elf64_Shdr));
  }
};

ElfImage read_image(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw Error(file.string() + ": cannot be read");
  ElfImage image;
  image.bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  image.header = image.at<Elf64_Ehdr>(0);
  if (!image.header || std::memcmp(image.header->e_ident, ELFMAG, SELFMAG) != 0 ||
      image.header->e_ident[EI_CLASS] != ELFCLASS64 ||
      image.header->e_ident[EI_DATA] != ELFDATA2LSB || !image.section(0) ||
      image.header->e_shentsize != sizeof(Elf64_Shdr))
    throw Error(file.string() + ": not a 64-bit ELF shared library");
  return image;
}

// Calls visit(symbol, name) for every defined dynamic symbol.
template <class Visit>
void for_each_dynamic_symbol(const ElfImage& image, Visit visit) {
  for (std::size_t i = 0; i < image.header->e_shnum; ++i) {
    const Elf64_Shdr* table = image.section(i);
    if (!table || table->sh_type != SHT_DYNSYM) continue;
    const Elf64_Shdr* strings = image.section(table->sh_link);
    if (!strings || table->sh_entsize != sizeof(Elf64_Sym)) continue;
    const std::size_t count = table->sh_size / sizeof(Elf64_Sym);
    const auto* symbols = image.at<Elf64_Sym>(table->sh_offset, count);
    if (!symbols) continue;
    for (std::size_t k = 0; k < count; ++k) {
      const Elf64_Sym& symbol = symbols[k];
      if (symbol.st_shndx == SHN_UNDEF || symbol.st_name >= strings->sh_size) continue;
      const char* name = image.at<char>(strings->sh_offset + symbol.st_name);
      if (!name) continue;
      const std::size_t max_length = strings->sh_size - symbol.st_name;
      visit(symbol, std::string(name, strnlen(name, max_length)));
    }
  }
}

}  // namespace

bool SymbolTable::has(const std::string& name) const {
  return std::find(names.begin(), names.end(), name) != names.end();
}

SymbolTable dynamic_symbols(const std::filesystem::path& file) {
  const ElfImage image = read_image(file);
  SymbolTable table;
  for_each_dynamic_symbol(
      image, [&](const Elf64_Sym&, std::string name) { table.names.push_back(std::move(name)); });
  return table;
}

std::optional<std::vector<char>> symbol_bytes(const std::filesystem::path& file,
                                              const std::string& name) {
  const ElfImage image = read_image(file);
  std::optional<std::vector<char>> result;
  for_each_dynamic_symbol(image, [&](const Elf64_Sym& symbol, const std::string& symbol_name) {
    if (result || symbol_name != name || symbol.st_shndx >= image.header->e_shnum) return;
    const Elf64_Shdr* section = image.section(symbol.st_shndx);
    if (!section || section->sh_type == SHT_NOBITS || symbol.st_value < section->sh_addr) return;
    const std::uint64_t offset = section->sh_offset + (symbol.st_value - section->sh_addr);
    const char* data = image.at<char>(offset, symbol.st_size);
    if (data) result.emplace(data, data + symbol.st_size);
  });
  return result;
}

}  // namespace prt::elf
