// PSNR and SSIM on 8-bit images, in double, as scikit-image defines them.
#include "prt/image_metrics.hpp"

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "prt/error.hpp"

namespace prt {

namespace {

void check_sizes(const Image8& a, const Image8& b, const char* metric) {
  if (a.width != b.width || a.height != b.height ||
      a.rgb.size() != 3 * std::size_t(a.width) * std::size_t(a.height) ||
      b.rgb.size() != a.rgb.size())
    throw Error(std::string(metric) + ": the images differ in size (" + std::to_string(a.width) +
                " x " + std::to_string(a.height) + " and " + std::to_string(b.width) + " x " +
                std::to_string(b.height) + ")");
}

// scipy.ndimage's Gaussian kernel: radius int(3.5 sigma + 0.5), normalised.
constexpr double kSigma = 1.5;
constexpr int kRadius = 5;

std::vector<double> gaussian_kernel() {
  std::vector<double> kernel(2 * kRadius + 1);
  double sum = 0;
  for (int i = -kRadius; i <= kRadius; ++i)
    sum += kernel[std::size_t(i + kRadius)] = std::exp(-0.5 * i * i / (kSigma * kSigma));
  for (double& w : kernel) w /= sum;
  return kernel;
}

// One plane filtered by the separable kernel at the pixels whose window
// lies inside the image (the only ones SSIM's mean keeps).
std::vector<double> filtered(const std::vector<double>& plane, int width, int height,
                             const std::vector<double>& kernel) {
  std::vector<double> rows(plane.size(), 0.0), out(plane.size(), 0.0);
  for (int y = 0; y < height; ++y)
    for (int x = kRadius; x < width - kRadius; ++x) {
      double sum = 0;
      for (int k = -kRadius; k <= kRadius; ++k)
        sum += kernel[std::size_t(k + kRadius)] * plane[std::size_t(y) * width + x + k];
      rows[std::size_t(y) * width + x] = sum;
    }
  for (int y = kRadius; y < height - kRadius; ++y)
    for (int x = kRadius; x < width - kRadius; ++x) {
      double sum = 0;
      for (int k = -kRadius; k <= kRadius; ++k)
        sum += kernel[std::size_t(k + kRadius)] * rows[std::size_t(y + k) * width + x];
      out[std::size_t(y) * width + x] = sum;
    }
  return out;
}

}  // namespace

double psnr(const Image8& a, const Image8& b) {
  check_sizes(a, b, "PSNR");
  double squares = 0;
  for (std::size_t i = 0; i < a.rgb.size(); ++i) {
    const double d = double(a.rgb[i]) - double(b.rgb[i]);
    squares += d * d;
  }
  if (squares == 0) return std::numeric_limits<double>::infinity();
  return 10.0 * std::log10(255.0 * 255.0 / (squares / double(a.rgb.size())));
}

double ssim(const Image8& a, const Image8& b) {
  check_sizes(a, b, "SSIM");
  const int width = a.width, height = a.height;
  if (width < 2 * kRadius + 1 || height < 2 * kRadius + 1)
    throw Error("SSIM: the images are " + std::to_string(width) + " x " + std::to_string(height) +
                " pixels; its 11 x 11 window needs at least that");
  const std::vector<double> kernel = gaussian_kernel();
  const double c1 = std::pow(0.01 * 255, 2), c2 = std::pow(0.03 * 255, 2);
  const std::size_t n = std::size_t(width) * std::size_t(height);
  double total = 0;
  for (int c = 0; c < 3; ++c) {
    std::vector<double> x(n), y(n), xx(n), yy(n), xy(n);
    for (std::size_t p = 0; p < n; ++p) {
      x[p] = a.rgb[3 * p + c], y[p] = b.rgb[3 * p + c];
      xx[p] = x[p] * x[p], yy[p] = y[p] * y[p], xy[p] = x[p] * y[p];
    }
    const auto ux = filtered(x, width, height, kernel), uy = filtered(y, width, height, kernel);
    const auto uxx = filtered(xx, width, height, kernel);
    const auto uyy = filtered(yy, width, height, kernel);
    const auto uxy = filtered(xy, width, height, kernel);
    double sum = 0;
    for (int py = kRadius; py < height - kRadius; ++py)
      for (int px = kRadius; px < width - kRadius; ++px) {
        const std::size_t p = std::size_t(py) * width + px;
        const double vx = uxx[p] - ux[p] * ux[p], vy = uyy[p] - uy[p] * uy[p];
        const double vxy = uxy[p] - ux[p] * uy[p];
        sum += (2 * ux[p] * uy[p] + c1) * (2 * vxy + c2) /
               ((ux[p] * ux[p] + uy[p] * uy[p] + c1) * (vx + vy + c2));
      }
    total += sum / (double(width - 2 * kRadius) * double(height - 2 * kRadius));
  }
  return total / 3;
}

}  // namespace prt
