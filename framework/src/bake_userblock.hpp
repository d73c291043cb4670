// The first 512 bytes of a bake file: an HDF5 user block (HDF5 skips it) that
// holds a magic line, the file's length and a CRC-32 of every byte after the
// block. It is checked before libhdf5 parses anything, so a damaged or
// truncated file is refused without reaching the library's parser.
#pragma once
#include <cstdint>
#include <filesystem>

namespace prt {

inline constexpr char kBakeMagic[] = "PRT-BAKE\n";
inline constexpr std::uint64_t kBakeUserBlockSize = 512;

// Fills the user block of a finished HDF5 file written with that block size,
// every read and write checked (write_atomically flushes it to the device); messages
// name `shown` (the user's name for the file) when given.
void seal_bake_file(const std::filesystem::path& file, int format_version,
                    const std::filesystem::path& shown = {});

// Throws prt::Error naming the file unless its block, length and checksum
// agree; returns the format version the block declares.
int verify_bake_file(const std::filesystem::path& file);

}  // namespace prt
