// Linear RGB images and PNG output.
#pragma once
#include <cstdint>
#include <filesystem>
#include <vector>

namespace prt {

struct Image {
  int width = 0, height = 0;
  std::vector<float> rgb;  // linear, row-major, top row first

  Image() = default;
  Image(int w, int h) : width(w), height(h), rgb(static_cast<std::size_t>(w) * h * 3, 0.f) {}
  float* at(int x, int y) { return &rgb[(static_cast<std::size_t>(y) * width + x) * 3]; }
  const float* at(int x, int y) const {
    return &rgb[(static_cast<std::size_t>(y) * width + x) * 3];
  }
};

// Writes exposure-scaled, sRGB-encoded 8-bit PNG atomically (temp + rename).
void write_png(const Image& image, const std::filesystem::path& file, float exposure = 1.0f);

// Writes the linear radiance as OpenEXR (RGB, 32-bit float, no exposure:
// what a paper's figures and other tools compute with), atomically.
void write_exr(const Image& image, const std::filesystem::path& file);

// The image file a path names by its extension: .png (exposure-scaled,
// sRGB) or .exr (linear float); any other is refused with both named.
enum class ImageFormat { png, exr };
ImageFormat image_format(const std::filesystem::path& file);
void write_image(const Image& image, const std::filesystem::path& file, float exposure = 1.0f);

// An 8-bit image file as written (RGB, 0..255, top row first), for comparing
// renderings; throws prt::Error naming the file when it cannot be read.
struct Image8 {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
};
Image8 read_png(const std::filesystem::path& file);
// The image as a PNG shows it: exposure-scaled, clamped, sRGB-encoded to 8 bits.
Image8 display_image(const Image& image, float exposure = 1.0f);
// Writes 8-bit RGB as PNG atomically (temp + rename), every write checked.
void write_png(const Image8& image, const std::filesystem::path& file);

// Mean absolute difference of two images of the same size (linear values).
double mean_absolute_difference(const Image& a, const Image& b);

// Pixels far darker than the truth, as displayed: the artifact a good RMS
// hides (a contour of black speckles). Both images are exposure-scaled and
// sRGB-encoded to 8 bits as write_png does; a pixel counts when the truth's
// luminance (Rec. 709 weights, 0..255) is above `lit` and the image's is below
// `fraction` of it.
struct DarkPixels {
  long long dark = 0;  // darker than fraction x the truth
  long long lit = 0;   // pixels whose truth is above the threshold
};
DarkPixels count_dark_pixels(const Image& image, const Image& truth, float exposure,
                             double lit = 40, double fraction = 0.5);

}  // namespace prt
