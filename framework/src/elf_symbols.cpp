#include "elf_symbols.hpp"

#include <elf.h>

#include <algorithm>
#include <cstring>
#include <fstream>

#include "prt/error.hpp"

namespace prt::elf {
namespace {

// Limits far above any real plug-in: a declared size past them, or past the
// file's end, is damage and is refused before anything is allocated.
constexpr std::uint64_t kMaxTableBytes = 64ull << 20;
constexpr std::uint64_t kMaxSymbolBytes = 1ull << 20;

// Reads only the parts of the file it is asked for, each checked against the
// file's size: a 1 GiB file costs a few kilobytes to inspect.
class ElfFile {
 public:
  explicit ElfFile(const std::filesystem::path& file)
      : where_(file.string()), in_(file, std::ios::binary) {
    std::error_code error;
    size_ = std::filesystem::file_size(file, error);
    if (!in_ || error) throw Error(where_ + ": cannot be read");
    if (!read_into(0, &header_, sizeof header_) ||
        std::memcmp(header_.e_ident, ELFMAG, SELFMAG) != 0 ||
        header_.e_ident[EI_CLASS] != ELFCLASS64 || header_.e_ident[EI_DATA] != ELFDATA2LSB ||
        header_.e_shentsize != sizeof(Elf64_Shdr) || header_.e_shnum == 0)
      throw Error(where_ + ": not a 64-bit ELF shared library");
    sections_.resize(header_.e_shnum);
    if (!read_into(header_.e_shoff, sections_.data(), sections_.size() * sizeof(Elf64_Shdr)))
      throw Error(where_ + ": damaged ELF file (section headers lie past its end)");
  }

  const std::vector<Elf64_Shdr>& sections() const { return sections_; }

  // A section's bytes, or nothing when it lies outside the file or is too big.
  std::optional<std::vector<char>> bytes(std::uint64_t offset, std::uint64_t size,
                                         std::uint64_t limit) {
    if (size > limit) return std::nullopt;
    std::vector<char> out(size);
    if (!read_into(offset, out.data(), size)) return std::nullopt;
    return out;
  }

 private:
  bool read_into(std::uint64_t offset, void* out, std::uint64_t size) {
    if (offset > size_ || size > size_ - offset) return false;
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(offset));
    in_.read(static_cast<char*>(out), static_cast<std::streamsize>(size));
    return static_cast<std::uint64_t>(in_.gcount()) == size;
  }

  std::string where_;
  std::ifstream in_;
  std::uint64_t size_ = 0;
  Elf64_Ehdr header_{};
  std::vector<Elf64_Shdr> sections_;
};

// Calls visit(symbol, name) for every defined dynamic symbol.
template <class Visit>
void for_each_dynamic_symbol(ElfFile& elf, Visit visit) {
  const auto& sections = elf.sections();
  for (const Elf64_Shdr& table : sections) {
    if (table.sh_type != SHT_DYNSYM || table.sh_entsize != sizeof(Elf64_Sym) ||
        table.sh_link >= sections.size())
      continue;
    const Elf64_Shdr& strings = sections[table.sh_link];
    const auto symbol_data = elf.bytes(table.sh_offset, table.sh_size, kMaxTableBytes);
    const auto names = elf.bytes(strings.sh_offset, strings.sh_size, kMaxTableBytes);
    if (!symbol_data || !names) continue;
    const std::size_t count = symbol_data->size() / sizeof(Elf64_Sym);
    for (std::size_t k = 0; k < count; ++k) {
      Elf64_Sym symbol;
      std::memcpy(&symbol, symbol_data->data() + k * sizeof symbol, sizeof symbol);
      if (symbol.st_shndx == SHN_UNDEF || symbol.st_name >= names->size()) continue;
      const char* name = names->data() + symbol.st_name;
      visit(symbol, std::string(name, strnlen(name, names->size() - symbol.st_name)));
    }
  }
}

}  // namespace

bool SymbolTable::has(const std::string& name) const {
  return std::find(names.begin(), names.end(), name) != names.end();
}

SymbolTable dynamic_symbols(const std::filesystem::path& file) {
  ElfFile elf(file);
  SymbolTable table;
  for_each_dynamic_symbol(
      elf, [&](const Elf64_Sym&, std::string name) { table.names.push_back(std::move(name)); });
  return table;
}

std::optional<std::vector<char>> symbol_bytes(const std::filesystem::path& file,
                                              const std::string& name) {
  ElfFile elf(file);
  const auto& sections = elf.sections();
  std::optional<Elf64_Sym> found;
  for_each_dynamic_symbol(elf, [&](const Elf64_Sym& symbol, const std::string& symbol_name) {
    if (!found && symbol_name == name) found = symbol;
  });
  if (!found || found->st_shndx >= sections.size()) return std::nullopt;
  const Elf64_Shdr& section = sections[found->st_shndx];
  if (section.sh_type == SHT_NOBITS || found->st_value < section.sh_addr ||
      found->st_value - section.sh_addr > section.sh_size)
    return std::nullopt;
  const std::uint64_t offset = section.sh_offset + (found->st_value - section.sh_addr);
  if (offset < section.sh_offset) return std::nullopt;  // wrapped around
  return elf.bytes(offset, found->st_size, kMaxSymbolBytes);
}

}  // namespace prt::elf
