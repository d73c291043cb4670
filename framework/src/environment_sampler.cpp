#include "prt/environment_sampler.hpp"

#include <algorithm>
#include <cmath>

#include "prt/direction_set.hpp"

namespace prt {

namespace {
// Index i with cdf[i] <= u < cdf[i + 1], skipping empty intervals.
int find_interval(const double* cdf, int count, double u) {
  const double* it = std::upper_bound(cdf, cdf + count + 1, u);
  return std::clamp(static_cast<int>(it - cdf) - 1, 0, count - 1);
}
}  // namespace

EnvironmentSampler::EnvironmentSampler(const Environment& env)
    : width_(env.width()), height_(env.height()), rotation_(env.rotation()) {
  const auto& rgb = env.pixels();
  texel_probability_.assign(static_cast<std::size_t>(width_) * height_, 0.0);
  column_cdf_.assign(static_cast<std::size_t>(height_) * (width_ + 1), 0.0);
  row_cdf_.assign(height_ + 1, 0.0);
  row_z_.resize(height_ + 1);
  for (int y = 0; y <= height_; ++y) row_z_[y] = std::cos(M_PI * y / height_);
  texel_solid_angle_.resize(height_);
  for (int y = 0; y < height_; ++y)
    texel_solid_angle_[y] = (2.0 * M_PI / width_) * (row_z_[y] - row_z_[y + 1]);
  double total = 0;
  for (int y = 0; y < height_; ++y) {
    const double solid_angle = std::cos(M_PI * y / height_) - std::cos(M_PI * (y + 1) / height_);
    double* cdf = &column_cdf_[static_cast<std::size_t>(y) * (width_ + 1)];
    for (int x = 0; x < width_; ++x) {
      const float* p = &rgb[(static_cast<std::size_t>(y) * width_ + x) * 3];
      // A small floor keeps every direction samplable (the estimator stays
      // unbiased); the magnitude serves maps with negative texels too (a
      // band-limited light's ringing).
      const double weight =
          (std::abs(0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) + 1e-6) * solid_angle;
      texel_probability_[static_cast<std::size_t>(y) * width_ + x] = weight;
      cdf[x + 1] = cdf[x] + weight;
    }
    row_cdf_[y + 1] = row_cdf_[y] + cdf[width_];
    total += cdf[width_];
  }
  for (auto& p : texel_probability_) p /= total;
  for (auto& c : row_cdf_) c /= total;
  for (int y = 0; y < height_; ++y) {
    double* cdf = &column_cdf_[static_cast<std::size_t>(y) * (width_ + 1)];
    const double row_total = cdf[width_];
    for (int x = 0; x <= width_; ++x)
      cdf[x] = row_total > 0 ? cdf[x] / row_total : double(x) / width_;
  }
}

EnvironmentSampler::Drawn EnvironmentSampler::draw(double u1, double u2) const {
  const int y = find_interval(row_cdf_.data(), height_, u1);
  const double row_width = row_cdf_[y + 1] - row_cdf_[y];
  const double fy = row_width > 0 ? (u1 - row_cdf_[y]) / row_width : 0.5;
  const std::size_t row = static_cast<std::size_t>(y) * (width_ + 1);
  const double* cdf = &column_cdf_[row];
  const int x = find_interval(cdf, width_, u2);
  const double column_width = cdf[x + 1] - cdf[x];
  const double fx = column_width > 0 ? (u2 - cdf[x]) / column_width : 0.5;
  // Uniform in solid angle inside the texel, so pdf() is exact: z = cos
  // theta uniform between the row's bounds, then equirect_direction's
  // convention with sin theta from z (no acos and back).
  const double z0 = row_z_[y], z1 = row_z_[y + 1];
  const double z = std::clamp(z0 + std::clamp(fy, 0.0, 1.0) * (z1 - z0), -1.0, 1.0);
  const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
  const double phi = 2.0 * M_PI * ((x + std::clamp(fx, 0.0, 1.0)) / width_ - 0.5);
  const Eigen::Vector3d local(s * std::sin(phi), z, -s * std::cos(phi));
  return {rotation_ * local, Eigen::Index(y) * width_ + x};
}

EnvironmentSampler::Sample EnvironmentSampler::sample(double u1, double u2) const {
  const Drawn drawn = draw(u1, u2);
  // The texel it was drawn in gives its density and its radiance: its
  // centre's coordinates (no atan2 back from the direction).
  const Eigen::Index x = drawn.texel % width_, y = drawn.texel / width_;
  const Eigen::Vector2d centre((x + 0.5) / width_, (y + 0.5) / height_);
  return {drawn.direction, density(drawn.texel), centre};
}

double EnvironmentSampler::pdf(const Eigen::Vector3d& direction) const {
  return pdf_at(equirect_uv(rotation_.transpose() * direction));
}

Eigen::Index EnvironmentSampler::texel_at(const Eigen::Vector2d& uv) const {
  const int x = std::clamp(static_cast<int>(uv.x() * width_), 0, width_ - 1);
  const int y = std::clamp(static_cast<int>(uv.y() * height_), 0, height_ - 1);
  return Eigen::Index(y) * width_ + x;
}

double EnvironmentSampler::pdf_at(const Eigen::Vector2d& uv) const {
  return density(texel_at(uv));
}

}  // namespace prt
