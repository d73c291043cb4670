#include "prt/image.hpp"

// The one translation unit that holds stb's implementations.
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

#include <algorithm>
#include <cmath>

#include "prt/error.hpp"
#include "prt/output_file.hpp"

namespace prt {

namespace {
std::uint8_t encode_srgb(float linear) {
  const float x = std::clamp(std::isfinite(linear) ? linear : 0.f, 0.f, 1.f);
  const float s = x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.f / 2.4f) - 0.055f;
  return static_cast<std::uint8_t>(std::lround(s * 255.f));
}
}  // namespace

void write_png(const Image& image, const std::filesystem::path& file, float exposure) {
  if (image.width <= 0 || image.height <= 0)
    throw Error(file.string() + ": cannot write a PNG of " + std::to_string(image.width) + " x " +
                std::to_string(image.height) + " pixels (a PNG needs at least one)");
  if (image.rgb.size() != 3 * std::size_t(image.width) * std::size_t(image.height))
    throw Error(file.string() + ": the image holds " + std::to_string(image.rgb.size()) +
                " values for " + std::to_string(image.width) + " x " +
                std::to_string(image.height) + " RGB pixels");
  if (!std::isfinite(exposure) || exposure < 0)
    throw Error(file.string() + ": exposure " + std::to_string(exposure) +
                " is not a finite non-negative number");
  write_png(display_image(image, exposure), file);
}

Image8 display_image(const Image& image, float exposure) {
  Image8 out{image.width, image.height, std::vector<std::uint8_t>(image.rgb.size())};
  for (std::size_t i = 0; i < out.rgb.size(); ++i)
    out.rgb[i] = encode_srgb(image.rgb[i] * exposure);
  return out;
}

void write_png(const Image8& image, const std::filesystem::path& file) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != 3 * std::size_t(image.width) * std::size_t(image.height))
    throw Error(file.string() + ": cannot write a PNG of " + std::to_string(image.width) + " x " +
                std::to_string(image.height) + " pixels from " + std::to_string(image.rgb.size()) +
                " values");
  // Encoded in memory, then written with every write checked (stb's own
  // file writer ignores fwrite's failures: a full disk gave a cut PNG).
  std::vector<std::uint8_t> encoded;
  const auto append = [](void* context, void* data, int size) {
    auto* out = static_cast<std::vector<std::uint8_t>*>(context);
    const auto* from = static_cast<const std::uint8_t*>(data);
    out->insert(out->end(), from, from + size);
  };
  if (!stbi_write_png_to_func(append, &encoded, image.width, image.height, 3, image.rgb.data(),
                              image.width * 3) ||
      encoded.empty())
    throw Error(file.string() + ": cannot encode the PNG");
  write_atomically(file, [&](const std::filesystem::path& temporary) {
    write_bytes_checked(temporary, encoded.data(), encoded.size(), file);
  });
}

double mean_absolute_difference(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height) throw Error("images differ in size");
  double sum = 0;
  for (std::size_t i = 0; i < a.rgb.size(); ++i) sum += std::abs(double(a.rgb[i]) - b.rgb[i]);
  return a.rgb.empty() ? 0.0 : sum / a.rgb.size();
}

DarkPixels count_dark_pixels(const Image& image, const Image& truth, float exposure, double lit,
                             double fraction) {
  if (image.width != truth.width || image.height != truth.height)
    throw Error("images differ in size");
  const auto luminance = [exposure](const float* rgb) {
    return 0.2126 * encode_srgb(rgb[0] * exposure) + 0.7152 * encode_srgb(rgb[1] * exposure) +
           0.0722 * encode_srgb(rgb[2] * exposure);
  };
  DarkPixels count;
  for (std::size_t i = 0; i + 2 < truth.rgb.size(); i += 3) {
    const double expected = luminance(&truth.rgb[i]);
    if (expected <= lit) continue;
    ++count.lit;
    if (luminance(&image.rgb[i]) < fraction * expected) ++count.dark;
  }
  return count;
}

Image8 read_png(const std::filesystem::path& file) {
  int width = 0, height = 0, channels = 0;
  unsigned char* pixels = stbi_load(file.string().c_str(), &width, &height, &channels, 3);
  if (!pixels) throw Error(file.string() + ": cannot read image (" + stbi_failure_reason() + ")");
  Image8 image{width, height, std::vector<std::uint8_t>(pixels, pixels + 3 * width * height)};
  stbi_image_free(pixels);
  return image;
}

}  // namespace prt
