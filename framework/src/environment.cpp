#include "prt/environment.hpp"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <stb/stb_image.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "image_file_check.hpp"
#include "prt/camera.hpp"
#include "prt/error.hpp"
#include "prt/image.hpp"
#include "prt/log.hpp"
#include "prt/quadrature.hpp"

namespace prt {

Eigen::Matrix3d rotation_about_up(double degrees) {
  return Eigen::AngleAxisd(degrees * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
}

namespace {
void require_file(const std::filesystem::path& file) {
  if (!std::filesystem::is_regular_file(file))
    throw Error(file.string() + ": environment map not found");
}

// Radiance beyond this is damage, not light (an RGBE exponent of 255 decodes
// to ~1.7e38): sums over a map's pixels would overflow to infinity.
constexpr float kMaxRadiance = 1e20f;

std::string pixel_name(int x, int y) {
  return "pixel (" + std::to_string(x) + ", " + std::to_string(y) + ")";
}

// NaN, infinite and implausibly large values are refused with the pixel;
// negative ones are clamped to 0. A filtered or denoised map rings a little
// below 0 (Blender's courtyard.exr: 1,818 values, the lowest -0.003): that is
// clamped quietly; negative values holding more than 0.1% of the map's
// energy are not ringing, and a warning counts them.
std::vector<float> checked_pixels(const std::filesystem::path& file, const float* data, int width,
                                  int height, int channels) {
  std::vector<float> rgb(static_cast<std::size_t>(width) * height * 3);
  std::size_t negative = 0;
  double negative_sum = 0, positive_sum = 0;
  float lowest = 0;
  int lowest_x = 0, lowest_y = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c) {
        const float value = data[(static_cast<std::size_t>(y) * width + x) * channels + c];
        if (!std::isfinite(value))
          throw Error(file.string() + ": " + pixel_name(x, y) + " is NaN or infinite");
        if (std::abs(value) > kMaxRadiance) {
          char text[160];
          std::snprintf(text, sizeof text,
                        " holds %g, beyond the %g this reader accepts as radiance (damaged, or "
                        "an RGBE exponent of 255?)",
                        double(value), double(kMaxRadiance));
          throw Error(file.string() + ": " + pixel_name(x, y) + text);
        }
        if (value < 0) {
          ++negative;
          negative_sum -= value;
          if (value < lowest) lowest = value, lowest_x = x, lowest_y = y;
        } else {
          positive_sum += value;
        }
        rgb[(static_cast<std::size_t>(y) * width + x) * 3 + c] = std::max(value, 0.f);
      }
  if (negative > 0 && negative_sum > 1e-3 * positive_sum) {
    // A map with no positive value has no energy to compare them with.
    char share[64] = "no positive value in the map";
    if (positive_sum > 0)
      std::snprintf(share, sizeof share, "%.2g%% of the map's energy",
                    100 * negative_sum / positive_sum);
    char text[240];
    std::snprintf(text, sizeof text,
                  ": %zu negative value(s), %s, clamped to 0 (the lowest, %g, at ", negative, share,
                  double(lowest));
    log_warning(file.string() + text + pixel_name(lowest_x, lowest_y) + ")");
  }
  return rgb;
}
}  // namespace

Environment Environment::load(const std::filesystem::path& file) {
  std::string extension = file.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), ::tolower);
  if (extension == ".hdr") return load_hdr(file);
  if (extension == ".exr") return load_exr(file);
  throw Error(file.string() + ": unknown environment map format \"" + extension +
              "\"; use .exr (OpenEXR) or .hdr (Radiance)");
}

Environment Environment::load_hdr(const std::filesystem::path& file) {
  require_file(file);
  check_radiance_file(file);
  int width = 0, height = 0, channels = 0;
  float* data = stbi_loadf(file.c_str(), &width, &height, &channels, 3);
  if (!data)
    throw Error(file.string() + ": cannot read Radiance HDR image: " + stbi_failure_reason());
  std::vector<float> rgb;
  try {
    rgb = checked_pixels(file, data, width, height, 3);
  } catch (...) {
    stbi_image_free(data);
    throw;
  }
  stbi_image_free(data);
  if (width < 2 || height < 1) throw Error(file.string() + ": environment map is too small");
  return from_pixels(width, height, std::move(rgb));
}

Environment Environment::load_exr(const std::filesystem::path& file) {
  require_file(file);
  check_exr_file(file);
  // Read as 32-bit floats, channel by channel: the RGBA interface converts
  // to half (finite floats above 65504 became infinite) and fills channels
  // the file lacks with 0 without a word.
  std::vector<float> flat;
  int width = 0, height = 0;
  try {
    Imf::InputFile in(file.string().c_str());
    const Imath::Box2i window = in.header().dataWindow();
    check_image_resolution(file, std::int64_t(window.max.x) - window.min.x + 1,
                           std::int64_t(window.max.y) - window.min.y + 1);
    width = window.max.x - window.min.x + 1;
    height = window.max.y - window.min.y + 1;
    const Imf::ChannelList& channels = in.header().channels();
    const bool rgb =
        channels.findChannel("R") && channels.findChannel("G") && channels.findChannel("B");
    const bool luminance = !rgb && channels.findChannel("Y");
    if (!rgb && !luminance) {
      std::string present, missing;
      for (auto it = channels.begin(); it != channels.end(); ++it)
        present += (present.empty() ? "" : ", ") + std::string(it.name());
      for (const char* name : {"R", "G", "B"})
        if (!channels.findChannel(name))
          missing += (missing.empty() ? "" : ", ") + std::string(name);
      throw Error(file.string() + ": the image has no " + missing + " channel (it has " +
                  (present.empty() ? "none" : present) +
                  "); an environment map needs R, G and B (or Y)");
    }
    flat.assign(static_cast<std::size_t>(width) * height * 3, 0.f);
    const std::size_t pixel = 3 * sizeof(float), row = pixel * static_cast<std::size_t>(width);
    char* origin = reinterpret_cast<char*>(flat.data()) -
                   static_cast<std::ptrdiff_t>(window.min.x) * std::ptrdiff_t(pixel) -
                   static_cast<std::ptrdiff_t>(window.min.y) * std::ptrdiff_t(row);
    Imf::FrameBuffer buffer;
    for (int c = 0; c < (rgb ? 3 : 1); ++c)
      buffer.insert(rgb ? std::string(1, "RGB"[c]) : std::string("Y"),
                    Imf::Slice(Imf::FLOAT, origin + c * sizeof(float), pixel, row));
    in.setFrameBuffer(buffer);
    in.readPixels(window.min.y, window.max.y);
    if (luminance)  // grey: Y in every channel
      for (std::size_t i = 0; i < flat.size(); i += 3) flat[i + 1] = flat[i + 2] = flat[i];
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(file.string() + ": cannot read OpenEXR image: " + e.what());
  }
  if (width < 2 || height < 1) throw Error(file.string() + ": environment map is too small");
  return from_pixels(width, height, checked_pixels(file, flat.data(), width, height, 3));
}

Environment Environment::constant(const Eigen::Vector3f& radiance) {
  return from_pixels(1, 1, {radiance.x(), radiance.y(), radiance.z()});
}

Environment Environment::from_pixels(int width, int height, std::vector<float> rgb) {
  if (rgb.size() != static_cast<std::size_t>(width) * height * 3)
    throw Error("environment: pixel count does not match its size");
  Environment e;
  e.width_ = width, e.height_ = height, e.rgb_ = std::move(rgb);
  return e;
}

Eigen::Vector3f Environment::texel(int x, int y) const {
  x = ((x % width_) + width_) % width_;  // wraps in longitude
  y = std::clamp(y, 0, height_ - 1);
  const float* p = &rgb_[(static_cast<std::size_t>(y) * width_ + x) * 3];
  return {p[0], p[1], p[2]};
}

Eigen::Vector3f Environment::radiance(const Eigen::Vector3d& direction) const {
  const Eigen::Vector2d uv = equirect_uv(rotation_.transpose() * direction);
  const double fx = uv.x() * width_ - 0.5, fy = uv.y() * height_ - 0.5;
  const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
  const float ax = static_cast<float>(fx - x0), ay = static_cast<float>(fy - y0);
  const Eigen::Vector3f top = (1 - ax) * texel(x0, y0) + ax * texel(x0 + 1, y0);
  const Eigen::Vector3f bottom = (1 - ax) * texel(x0, y0 + 1) + ax * texel(x0 + 1, y0 + 1);
  return intensity_ * ((1 - ay) * top + ay * bottom);
}

Eigen::Vector3f Environment::texel_radiance(const Eigen::Vector3d& direction) const {
  return texel_radiance_at(uv_of(direction));
}

Eigen::Vector2d Environment::uv_of(const Eigen::Vector3d& direction) const {
  return equirect_uv(rotation_.transpose() * direction);
}

Eigen::Vector3f Environment::texel_radiance_at(const Eigen::Vector2d& uv) const {
  return intensity_ * texel(static_cast<int>(uv.x() * width_), static_cast<int>(uv.y() * height_));
}

Eigen::MatrixX3d Environment::project(const Basis& basis) const {
  const bool rotated = !rotation_.isIdentity(1e-12);
  const bool rotate_coefficients = rotated && basis.can_rotate();
  if (width_ == 1 && height_ == 1) {
    // A constant: exact quadrature (for polynomial bases up to order 64).
    const DirectionSet set = gauss_product_sphere(64);
    const Eigen::MatrixXd samples =
        (intensity_ * texel(0, 0)).cast<double>() * Eigen::RowVectorXd::Ones(set.size());
    return basis.project(samples, set).transpose();
  }
  const int w = width_, h = height_;
  if (!rotated || rotate_coefficients)
    if (auto fast = basis.project_equirect(w, h, rgb_.data())) {
      Eigen::MatrixX3d light = double(intensity_) * *fast;
      if (rotate_coefficients) light = basis.rotation_matrix(rotation_) * light;
      return light;
    }
  constexpr int kRows = 8;
  const int blocks = (h + kRows - 1) / kRows;
  std::vector<Eigen::MatrixX3d> partial(blocks);
  tbb::parallel_for(0, blocks, [&](int b) {
    const int begin = b * kRows, end = std::min(h, begin + kRows);
    const DirectionSet set = DirectionSet::equirect(w, h, begin, end);
    Eigen::MatrixXd samples(3, set.size());
    for (Eigen::Index k = 0; k < set.size(); ++k) {
      Eigen::Vector3f value;
      if (rotated && !rotate_coefficients) {
        value = texel_radiance(set.directions.row(k).transpose());
      } else {
        const int x = static_cast<int>(k % w), y = begin + static_cast<int>(k / w);
        value = intensity_ * texel(x, y);
      }
      samples.col(k) = value.cast<double>();
    }
    partial[b] = basis.project(samples, set).transpose();
  });
  Eigen::MatrixX3d light = Eigen::MatrixX3d::Zero(basis.size(), 3);
  for (const auto& p : partial) light += p;  // fixed order: deterministic
  if (rotate_coefficients) light = basis.rotation_matrix(rotation_) * light;
  return light;
}

Environment Environment::band_limited(const Basis& basis, const Eigen::MatrixX3d& light) const {
  const bool constant = width_ == 1 && height_ == 1;
  const int w = constant ? 256 : width_, h = constant ? 128 : height_;
  std::vector<float> rgb(static_cast<std::size_t>(w) * h * 3);
  constexpr int kRows = 8;
  tbb::parallel_for(0, (h + kRows - 1) / kRows, [&](int b) {
    const int begin = b * kRows, end = std::min(h, begin + kRows);
    const DirectionSet set = DirectionSet::equirect(w, h, begin, end);
    const Eigen::MatrixX3d values = basis.evaluate(set.directions) * light;
    for (Eigen::Index k = 0; k < set.size(); ++k)
      for (int c = 0; c < 3; ++c)
        rgb[(static_cast<std::size_t>(begin) * w + std::size_t(k)) * 3 + c] =
            static_cast<float>(values(k, c));
  });
  return from_pixels(w, h, std::move(rgb));
}

void draw_environment(const Environment& environment, const Camera& camera, Image& image) {
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const Eigen::Vector3f l = environment.radiance(camera.ray(x + 0.5f, y + 0.5f).cast<double>());
      float* out = image.at(x, y);
      for (int c = 0; c < 3; ++c) out[c] = l[c];
    }
}

}  // namespace prt
