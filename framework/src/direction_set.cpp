#include "prt/direction_set.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "prt/error.hpp"

namespace prt {

Eigen::Vector3d equirect_direction(double u, double v) {
  const double phi = 2.0 * M_PI * (u - 0.5), theta = M_PI * v;
  const double s = std::sin(theta);
  return {s * std::sin(phi), std::cos(theta), -s * std::cos(phi)};
}

Eigen::Vector2d equirect_uv(const Eigen::Vector3d& d) {
  const double u = 0.5 + std::atan2(d.x(), -d.z()) / (2.0 * M_PI);
  const double v = std::acos(std::clamp(d.y(), -1.0, 1.0)) / M_PI;
  return {u, v};
}

DirectionSet DirectionSet::fibonacci(int count) {
  if (count < 1) throw Error("fibonacci direction set needs at least 1 direction");
  DirectionSet set{"fibonacci", Directions(count, 3),
                   Eigen::VectorXd::Constant(count, 4.0 * M_PI / count)};
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < count; ++k) {
    const double z = 1.0 - (2.0 * k + 1.0) / count;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden * k;
    set.directions.row(k) << r * std::cos(phi), r * std::sin(phi), z;
  }
  return set;
}

DirectionSet DirectionSet::stratified(int count, std::uint64_t seed) {
  if (count < 1) throw Error("stratified direction set needs at least 1 direction");
  // rows x cols strata of equal area in (cos theta, phi); leftover samples go
  // to a final partial row so exactly `count` directions are produced.
  const int rows = std::max(1, static_cast<int>(std::sqrt(count / 2.0)));
  const int cols = std::max(1, count / rows);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(0.0, 1.0);
  DirectionSet set{"stratified", Directions(count, 3),
                   Eigen::VectorXd::Constant(count, 4.0 * M_PI / count)};
  for (int k = 0; k < count; ++k) {
    const int row = std::min(k / cols, rows - 1);
    const int row_begin = row * cols;
    const int in_row = (row == rows - 1) ? count - row_begin : cols;
    const int col = k - row_begin;
    const double z = 1.0 - 2.0 * (row + jitter(rng)) / rows;
    const double phi = 2.0 * M_PI * (col + jitter(rng)) / in_row;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    set.directions.row(k) << r * std::cos(phi), r * std::sin(phi), z;
  }
  return set;
}

namespace {

// Solid angle subtended by the cube-face rectangle [0,x] x [0,y] at distance 1.
double area_element(double x, double y) {
  return std::atan2(x * y, std::sqrt(x * x + y * y + 1));
}

Eigen::Vector3d cube_direction(int face, double a, double b) {
  switch (face) {
    case 0:
      return {1, -b, -a};
    case 1:
      return {-1, -b, a};
    case 2:
      return {a, 1, b};
    case 3:
      return {a, -1, -b};
    case 4:
      return {a, -b, 1};
    default:
      return {-a, -b, -1};
  }
}

}  // namespace

void cubemap_coordinates(const Eigen::Vector3d& d, int& face, double& a, double& b) {
  // Inverse of cube_direction().
  const Eigen::Vector3d m = d.cwiseAbs();
  if (m.x() >= m.y() && m.x() >= m.z()) {
    face = d.x() > 0 ? 0 : 1;
    a = (d.x() > 0 ? -d.z() : d.z()) / m.x();
    b = -d.y() / m.x();
  } else if (m.y() >= m.z()) {
    face = d.y() > 0 ? 2 : 3;
    a = d.x() / m.y();
    b = (d.y() > 0 ? d.z() : -d.z()) / m.y();
  } else {
    face = d.z() > 0 ? 4 : 5;
    a = (d.z() > 0 ? d.x() : -d.x()) / m.z();
    b = -d.y() / m.z();
  }
}

int cubemap_texel(const Eigen::Vector3d& d, int resolution) {
  int face;
  double a, b;
  cubemap_coordinates(d, face, a, b);
  const int R = resolution;
  const int i = std::clamp(static_cast<int>((a + 1) * 0.5 * R), 0, R - 1);
  const int j = std::clamp(static_cast<int>((b + 1) * 0.5 * R), 0, R - 1);
  return (face * R + j) * R + i;
}

DirectionSet DirectionSet::cubemap(int resolution) {
  if (resolution < 1) throw Error("cube-map direction set needs resolution >= 1");
  const int R = resolution;
  DirectionSet set{"cubemap", Directions(6 * R * R, 3), Eigen::VectorXd(6 * R * R)};
  for (int face = 0; face < 6; ++face)
    for (int j = 0; j < R; ++j)
      for (int i = 0; i < R; ++i) {
        const double a0 = 2.0 * i / R - 1.0, a1 = 2.0 * (i + 1) / R - 1.0;
        const double b0 = 2.0 * j / R - 1.0, b1 = 2.0 * (j + 1) / R - 1.0;
        const int k = (face * R + j) * R + i;
        set.directions.row(k) = cube_direction(face, 0.5 * (a0 + a1), 0.5 * (b0 + b1)).normalized();
        set.weights[k] = area_element(a0, b0) - area_element(a0, b1) - area_element(a1, b0) +
                         area_element(a1, b1);
      }
  return set;
}

DirectionSet DirectionSet::equirect(int width, int height, int row_begin, int row_end) {
  const int rows = row_end - row_begin;
  DirectionSet set{"equirect", Directions(rows * width, 3), Eigen::VectorXd(rows * width)};
  const double dphi = 2.0 * M_PI / width;
  for (int y = row_begin; y < row_end; ++y) {
    // Exact solid angle of the texel row: dphi * (cos theta0 - cos theta1).
    const double theta0 = M_PI * y / height, theta1 = M_PI * (y + 1) / height;
    const double weight = dphi * (std::cos(theta0) - std::cos(theta1));
    for (int x = 0; x < width; ++x) {
      const int k = (y - row_begin) * width + x;
      set.directions.row(k) = equirect_direction((x + 0.5) / width, (y + 0.5) / height);
      set.weights[k] = weight;
    }
  }
  return set;
}

DirectionSet DirectionSet::make(const std::string& kind, int count, std::uint64_t seed) {
  if (kind == "fibonacci") return fibonacci(count);
  if (kind == "stratified") return stratified(count, seed);
  if (kind == "cubemap") {
    const int resolution = std::max(1, static_cast<int>(std::lround(std::sqrt(count / 6.0))));
    return cubemap(resolution);
  }
  throw Error("unknown direction set \"" + kind + "\"; valid: fibonacci, stratified, cubemap");
}

}  // namespace prt
