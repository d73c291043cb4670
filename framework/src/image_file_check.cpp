#include "image_file_check.hpp"

#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "prt/error.hpp"

namespace prt {
namespace fs = std::filesystem;

void check_image_resolution(const fs::path& file, std::int64_t width, std::int64_t height) {
  const std::string where = file.string() + ": ";
  if (width < 1 || height < 1 || width > (1 << 20) || height > (1 << 20))
    throw Error(where + "image size " + std::to_string(width) + " x " + std::to_string(height) +
                " is out of range");
  std::error_code error;
  const double bytes = static_cast<double>(fs::file_size(file, error));
  const double pixels = static_cast<double>(width) * static_cast<double>(height);
  if (pixels > double(1 << 22) && pixels * 8 > 64 * bytes)
    throw Error(where + "the header declares " + std::to_string(width) + " x " +
                std::to_string(height) + " pixels, more than a file of " +
                std::to_string(static_cast<long long>(bytes)) + " bytes can hold (damaged?)");
}

namespace {
// An OpenEXR channel list: entries "name\0" + 16 bytes, ended by an empty
// name exactly at the end of the attribute.
bool channel_list_fills(const std::string& value) {
  std::size_t at = 0;
  while (at < value.size()) {
    const std::size_t end = value.find('\0', at);
    if (end == std::string::npos) return false;
    if (end == at) return end + 1 == value.size();
    at = end + 1 + 16;
  }
  return false;
}
}  // namespace

void check_exr_file(const fs::path& file) {
  // OpenEXR allocates what each header attribute declares before reading
  // it; here every declared size must fit in what is left of the file.
  const std::string where = file.string() + ": ";
  std::ifstream in(file, std::ios::binary);
  std::error_code error;
  const std::uint64_t size = fs::file_size(file, error);
  unsigned char head[8] = {};
  in.read(reinterpret_cast<char*>(head), 8);
  if (in.gcount() != 8 || head[0] != 0x76 || head[1] != 0x2f || head[2] != 0x31 || head[3] != 0x01)
    throw Error(where + "not an OpenEXR image (no EXR magic number)");
  const bool multipart = head[5] & 0x10;
  const std::size_t max_name = (head[5] & 0x04) ? 255 : 31;
  auto read_name = [&](std::string& name) {
    name.clear();
    for (char c; in.get(c);) {
      if (c == '\0') return true;
      if (name.size() >= max_name) return false;
      name += c;
    }
    return false;
  };
  std::string name, type;
  for (int headers = 0; headers < 1000; ++headers) {
    int attributes = 0;
    for (;; ++attributes) {
      if (!read_name(name)) throw Error(where + "damaged OpenEXR header (attribute name)");
      if (name.empty()) break;  // the header's end
      std::int32_t bytes = 0;
      if (!read_name(type) || !in.read(reinterpret_cast<char*>(&bytes), 4))
        throw Error(where + "damaged OpenEXR header (attribute \"" + name + "\")");
      const auto at = static_cast<std::uint64_t>(in.tellg());
      if (bytes < 0 || static_cast<std::uint64_t>(bytes) > size - std::min(size, at))
        throw Error(where + "OpenEXR attribute \"" + name + "\" declares " + std::to_string(bytes) +
                    " bytes, more than the file holds (damaged?)");
      std::string value(static_cast<std::size_t>(bytes), '\0');
      in.read(value.data(), bytes);
      // OpenEXR reads these two by their contents, not their declared size:
      // the contents must agree with it, or its reading drifts off the header.
      if (type == "chlist" && !channel_list_fills(value))
        throw Error(where + "damaged OpenEXR channel list (its entries do not fill its " +
                    std::to_string(bytes) + " bytes)");
      if (type == "preview") {
        std::uint32_t w = 0, h = 0;
        if (value.size() >= 8)
          std::memcpy(&w, value.data(), 4), std::memcpy(&h, value.data() + 4, 4);
        if (value.size() < 8 || 4.0 * w * h + 8 != static_cast<double>(value.size()))
          throw Error(where + "damaged OpenEXR preview image (its size disagrees with its bytes)");
      }
    }
    if (!multipart || attributes == 0) return;  // single part, or the list's empty header
  }
  throw Error(where + "damaged OpenEXR header (too many parts)");
}

void check_radiance_file(const fs::path& file) {
  const std::string where = file.string() + ": ";
  std::ifstream in(file, std::ios::binary);
  std::string line;
  if (!std::getline(in, line) || (line.rfind("#?RADIANCE", 0) != 0 && line.rfind("#?RGBE", 0) != 0))
    throw Error(where + "not a Radiance HDR image (no #?RADIANCE line)");
  // Header lines end at an empty line; the resolution line follows.
  for (int lines = 0; std::getline(in, line) && !line.empty(); ++lines)
    if (lines > 1000) throw Error(where + "Radiance header without an end");
  if (!std::getline(in, line)) throw Error(where + "Radiance header without a resolution line");
  char y_axis[3] = {}, x_axis[3] = {};
  long long height = 0, width = 0;
  if (std::sscanf(line.c_str(), "%2s %lld %2s %lld", y_axis, &height, x_axis, &width) != 4 ||
      std::string(y_axis) != "-Y" || std::string(x_axis) != "+X")
    throw Error(where + "unsupported Radiance resolution line \"" + line.substr(0, 40) +
                "\" (expected -Y H +X W)");
  check_image_resolution(file, width, height);

  // Walk every scanline: new-style run-length (2 2 hi lo, then 4 channels of
  // runs) or flat RGBE. Old-style runs are not produced by today's writers.
  std::vector<unsigned char> buffer((std::istreambuf_iterator<char>(in)),
                                    std::istreambuf_iterator<char>());
  std::size_t at = 0;
  auto truncated = [&](long long y) {
    return Error(where + "truncated Radiance image: scanline " + std::to_string(y + 1) + " of " +
                 std::to_string(height) + " is incomplete");
  };
  for (long long y = 0; y < height; ++y) {
    const bool rle = width >= 8 && width < 32768 && at + 4 <= buffer.size() && buffer[at] == 2 &&
                     buffer[at + 1] == 2 && !(buffer[at + 2] & 0x80);
    if (!rle) {
      if (buffer.size() - at < static_cast<std::size_t>(4 * width)) throw truncated(y);
      at += 4 * width;
      continue;
    }
    if (((buffer[at + 2] << 8) | buffer[at + 3]) != width)
      throw Error(where + "damaged Radiance image: scanline " + std::to_string(y + 1) +
                  " has the wrong width");
    at += 4;
    for (int channel = 0; channel < 4; ++channel)
      for (long long x = 0; x < width;) {
        if (at >= buffer.size()) throw truncated(y);
        const int count = buffer[at++];
        const bool run = count > 128;
        const int n = run ? count - 128 : count;
        if (n == 0 || x + n > width)
          throw Error(where + "damaged Radiance image: bad run in scanline " +
                      std::to_string(y + 1));
        const std::size_t bytes = run ? 1 : static_cast<std::size_t>(n);
        if (buffer.size() - at < bytes) throw truncated(y);
        at += bytes;
        x += n;
      }
  }
}

}  // namespace prt
