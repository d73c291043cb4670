#include "bake_userblock.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <boost/crc.hpp>
#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <vector>

#include "prt/error.hpp"
#include "prt/output_file.hpp"

namespace prt {
namespace fs = std::filesystem;

namespace {

// CRC-32 of the bytes after the user block.
std::uint32_t checksum_after_block(std::istream& in) {
  boost::crc_32_type crc;
  std::vector<char> buffer(1 << 20);
  in.seekg(static_cast<std::streamoff>(kBakeUserBlockSize));
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    crc.process_bytes(buffer.data(), static_cast<std::size_t>(in.gcount()));
  }
  return crc.checksum();
}

}  // namespace

void seal_bake_file(const fs::path& file, int format_version, const fs::path& shown) {
  const fs::path& name = shown.empty() ? file : shown;
  const int descriptor = ::open(file.c_str(), O_RDWR | O_CLOEXEC);
  if (descriptor < 0) throw Error(io_failure(name, errno, "reopening the bake file to seal it"));
  struct Closer {
    int fd;
    ~Closer() {
      if (fd >= 0) ::close(fd);
    }
  } closer{descriptor};
  // The checksum is of what the file holds now, read back through the
  // kernel, not of what was meant to be written.
  boost::crc_32_type crc;
  std::vector<char> buffer(1 << 20);
  std::uint64_t length = kBakeUserBlockSize;
  for (;;) {
    const ssize_t got =
        ::pread(descriptor, buffer.data(), buffer.size(), static_cast<off_t>(length));
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) throw Error(io_failure(name, errno, "reading the bake file back to seal it"));
    if (got == 0) break;
    crc.process_bytes(buffer.data(), static_cast<std::size_t>(got));
    length += static_cast<std::uint64_t>(got);
  }
  char block[kBakeUserBlockSize] = {};
  std::snprintf(block, sizeof block,
                "%sformat %d\nlength %" PRIu64 "\ncrc32 %08" PRIx32
                "\n(a PRT bake file: HDF5 after this %d-byte block)\n",
                kBakeMagic, format_version, length, crc.checksum(), int(kBakeUserBlockSize));
  for (std::size_t done = 0; done < sizeof block;) {
    const ssize_t wrote =
        ::pwrite(descriptor, block + done, sizeof block - done, static_cast<off_t>(done));
    if (wrote < 0 && errno == EINTR) continue;
    if (wrote <= 0)
      throw Error(io_failure(name, wrote < 0 ? errno : ENOSPC, "writing the bake file's header"));
    done += static_cast<std::size_t>(wrote);
  }
  closer.fd = -1;  // flushed to the device by write_atomically, which renames it
  if (::close(descriptor) != 0) throw Error(io_failure(name, errno, "writing the bake file"));
}

int verify_bake_file(const fs::path& file) {
  const std::string where = file.string() + ": ";
  std::error_code error;
  const auto status = fs::status(file, error);
  if (!fs::exists(status)) throw Error(where + "bake file not found");
  if (!fs::is_regular_file(status)) throw Error(where + "not a regular file");
  const std::uint64_t size = fs::file_size(file, error);
  std::ifstream in(file, std::ios::binary);
  if (error || !in) throw Error(where + "cannot read the bake file");
  char block[kBakeUserBlockSize + 1] = {};
  in.read(block, kBakeUserBlockSize);
  static const char hdf5_signature[] = "\x89HDF\r\n\x1a\n";
  if (std::memcmp(block, kBakeMagic, sizeof kBakeMagic - 1) != 0) {
    if (std::memcmp(block, hdf5_signature, 8) == 0)
      throw Error(where +
                  "not a PRT bake file of this format (an HDF5 file without the "
                  "PRT-BAKE header: a bake of format version 2 or older, or another "
                  "HDF5 file); re-bake the scene");
    throw Error(where + "not a PRT bake file (no PRT-BAKE header)");
  }
  if (size < kBakeUserBlockSize)
    throw Error(where + "truncated bake file (" + std::to_string(size) + " bytes)");
  int version = 0;
  std::uint64_t length = 0;
  std::uint32_t stored = 0;
  if (std::sscanf(block + sizeof kBakeMagic - 1, "format %d\nlength %" SCNu64 "\ncrc32 %8" SCNx32,
                  &version, &length, &stored) != 3)
    throw Error(where + "damaged bake file header");
  if (length != size)
    throw Error(where + "truncated or extended bake file: its header says " +
                std::to_string(length) + " bytes, the file has " + std::to_string(size));
  const std::uint32_t computed = checksum_after_block(in);
  if (computed != stored) {
    char message[160];
    std::snprintf(message, sizeof message,
                  "checksum mismatch (stored crc32 %08" PRIx32 ", computed %08" PRIx32
                  "): the bake file is damaged",
                  stored, computed);
    throw Error(where + message);
  }
  return version;
}

}  // namespace prt
