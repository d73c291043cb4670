// OpenEXR output: the image encoded in memory (an Imf::OStream over a byte
// vector), then written with every write checked and renamed into place, as
// PNGs are (OpenEXR's own file stream would leave a cut file on a full disk).
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfOutputFile.h>

#include <algorithm>
#include <cstring>

#include "prt/error.hpp"
#include "prt/image.hpp"
#include "prt/output_file.hpp"

namespace prt {

namespace {

class MemoryStream final : public Imf::OStream {
 public:
  MemoryStream() : Imf::OStream("memory") {}
  void write(const char c[], int n) override {
    const auto end = std::size_t(at_) + std::size_t(n);
    if (bytes.size() < end) bytes.resize(end);
    std::memcpy(bytes.data() + at_, c, std::size_t(n));
    at_ = end;
  }
  std::uint64_t tellp() override { return at_; }
  void seekp(std::uint64_t position) override { at_ = position; }
  std::vector<char> bytes;

 private:
  std::uint64_t at_ = 0;
};

}  // namespace

void write_exr(const Image& image, const std::filesystem::path& file) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != 3 * std::size_t(image.width) * std::size_t(image.height))
    throw Error(file.string() + ": cannot write an OpenEXR image of " +
                std::to_string(image.width) + " x " + std::to_string(image.height) +
                " pixels from " + std::to_string(image.rgb.size()) + " values");
  MemoryStream stream;
  try {
    Imf::Header header(image.width, image.height);
    Imf::FrameBuffer frame;
    const std::size_t pixel = 3 * sizeof(float), row = pixel * std::size_t(image.width);
    auto* origin = const_cast<char*>(reinterpret_cast<const char*>(image.rgb.data()));
    for (int c = 0; c < 3; ++c) {
      const char* name = c == 0 ? "R" : c == 1 ? "G" : "B";
      header.channels().insert(name, Imf::Channel(Imf::FLOAT));
      frame.insert(name, Imf::Slice(Imf::FLOAT, origin + c * sizeof(float), pixel, row));
    }
    Imf::OutputFile out(stream, header);
    out.setFrameBuffer(frame);
    out.writePixels(image.height);
  } catch (const std::exception& e) {
    throw Error(file.string() + ": cannot encode the OpenEXR image (" + e.what() + ")");
  }
  write_atomically(file, [&](const std::filesystem::path& temporary) {
    write_bytes_checked(temporary, stream.bytes.data(), stream.bytes.size(), file);
  });
}

ImageFormat image_format(const std::filesystem::path& file) {
  std::string extension = file.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  if (extension == ".png") return ImageFormat::png;
  if (extension == ".exr") return ImageFormat::exr;
  throw Error(file.string() + ": unknown image type \"" + extension +
              "\"; name a .png (8-bit sRGB, exposure applied) or an .exr (linear float)");
}

void write_image(const Image& image, const std::filesystem::path& file, float exposure) {
  if (image_format(file) == ImageFormat::exr)
    write_exr(image, file);
  else
    write_png(image, file, exposure);
}

}  // namespace prt
