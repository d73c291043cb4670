#include "prt/image.hpp"

// The one translation unit that holds stb's implementations.
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

#include <algorithm>
#include <cmath>

#include "prt/bake_file.hpp"
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
  std::vector<std::uint8_t> bytes(image.rgb.size());
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = encode_srgb(image.rgb[i] * exposure);
  write_atomically(file, [&](const std::filesystem::path& temporary) {
    if (!stbi_write_png(temporary.c_str(), image.width, image.height, 3, bytes.data(),
                        image.width * 3))
      throw Error(file.string() + ": cannot write PNG");
  });
}

double mean_absolute_difference(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height) throw Error("images differ in size");
  double sum = 0;
  for (std::size_t i = 0; i < a.rgb.size(); ++i) sum += std::abs(double(a.rgb[i]) - b.rgb[i]);
  return a.rgb.empty() ? 0.0 : sum / a.rgb.size();
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
