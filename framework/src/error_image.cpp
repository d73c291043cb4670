// The heat map's colour ramp, its bar and its labels (stb_easy_font's quads,
// filled as rectangles: no font file needed).
#include "prt/error_image.hpp"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#include <stb/stb_easy_font.h>
#pragma GCC diagnostic pop

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "prt/error.hpp"

namespace prt {

namespace {

constexpr int kPanel = 140;  // pixels right of the image: the bar and its labels
constexpr int kMargin = 12, kBarWidth = 18;
constexpr int kTextScale = 2;  // stb_easy_font's glyphs are 7 pixels tall

// Viridis at five stops, interpolated in sRGB: ordered in lightness, readable
// in grey and by the colour-blind.
std::array<std::uint8_t, 3> ramp(double t) {
  static constexpr std::array<std::array<double, 3>, 5> stops{
      {{68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}}};
  t = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0) * (stops.size() - 1);
  const std::size_t i = std::min<std::size_t>(std::size_t(t), stops.size() - 2);
  const double f = t - double(i);
  std::array<std::uint8_t, 3> rgb{};
  for (int c = 0; c < 3; ++c)
    rgb[std::size_t(c)] = std::uint8_t(
        std::lround((1 - f) * stops[i][std::size_t(c)] + f * stops[i + 1][std::size_t(c)]));
  return rgb;
}

void fill(Image8& image, int x0, int y0, int x1, int y1, std::array<std::uint8_t, 3> rgb) {
  for (int y = std::max(0, y0); y < std::min(image.height, y1); ++y)
    for (int x = std::max(0, x0); x < std::min(image.width, x1); ++x)
      std::copy(rgb.begin(), rgb.end(), &image.rgb[(std::size_t(y) * image.width + x) * 3]);
}

// White text with its top left at (x, y), kTextScale times stb_easy_font's
// size: its quads are axis-aligned rectangles.
void print(Image8& image, int x, int y, const std::string& text) {
  std::vector<char> buffer(1024 * (text.size() + 1));  // at most 16 quads a glyph
  std::string copy = text;
  const int quads =
      stb_easy_font_print(0, 0, copy.data(), nullptr, buffer.data(), int(buffer.size()));
  for (int q = 0; q < quads; ++q) {
    const auto* v = reinterpret_cast<const float*>(buffer.data() + std::size_t(q) * 64);
    // Corners 0 and 2 of each quad (16 bytes a vertex: x, y, z, colour).
    const auto at = [&](float value, int origin) {
      return origin + int(std::lround(kTextScale * value));
    };
    fill(image, at(v[0], x), at(v[1], y), at(v[8], x), at(v[9], y), {255, 255, 255});
  }
}

std::string label(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", value);
  return text;
}

}  // namespace

Image signed_difference(const Image& render, const Image& truth) {
  if (render.width != truth.width || render.height != truth.height)
    throw Error("error image: the render and the ground truth differ in size");
  Image out(render.width, render.height);
  for (std::size_t i = 0; i < out.rgb.size(); ++i) out.rgb[i] = render.rgb[i] - truth.rgb[i];
  return out;
}

ErrorHeatMap error_heat_map(const Image& render, const Image& truth, float exposure) {
  const Image difference = signed_difference(render, truth);
  const int width = render.width, height = render.height;
  std::vector<double> error(std::size_t(width) * std::size_t(height));
  std::vector<double> differing;
  for (std::size_t p = 0; p < error.size(); ++p) {
    const float* d = &difference.rgb[3 * p];
    error[p] =
        exposure * (0.2126 * std::abs(d[0]) + 0.7152 * std::abs(d[1]) + 0.0722 * std::abs(d[2]));
    if (!std::isfinite(error[p])) error[p] = 0;
    if (error[p] > 0) differing.push_back(error[p]);
  }
  ErrorHeatMap out;
  if (!differing.empty()) {
    std::sort(differing.begin(), differing.end());
    out.peak = differing.back();
    out.top =
        differing[std::min(differing.size() - 1, std::size_t(0.99 * double(differing.size())))];
  }
  const double top = out.top > 0 ? out.top : 1.0;
  out.image = Image8{width + kPanel, height,
                     std::vector<std::uint8_t>(3 * std::size_t(width + kPanel) * height, 0)};
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      fill(out.image, x, y, x + 1, y + 1, ramp(error[std::size_t(y) * width + x] / top));
  // The bar: top value at the top, 0 at the bottom, labels beside it.
  const int bar_top = kMargin + 8 * kTextScale, bar_bottom = height - kMargin;
  const int bar_x = width + kMargin;
  for (int y = bar_top; y < bar_bottom; ++y)
    fill(out.image, bar_x, y, bar_x + kBarWidth, y + 1,
         ramp(double(bar_bottom - 1 - y) / std::max(1, bar_bottom - bar_top - 1)));
  const int text_x = bar_x + kBarWidth + 4;
  print(out.image, bar_x - 2, 2, "|error|");
  print(out.image, text_x, bar_top, label(top));
  print(out.image, text_x, (bar_top + bar_bottom) / 2 - 3 * kTextScale, label(top / 2));
  print(out.image, text_x, bar_bottom - 7 * kTextScale, "0");
  return out;
}

}  // namespace prt
