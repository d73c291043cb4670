// SH projection of an equirectangular image by a separable transform: per
// texel row, Fourier sums over longitude for m = 0..order-1, then associated
// Legendre values of the row's colatitude; O(h w order) instead of
// O(h w order^2) basis evaluations. The image's pole is +y while the SH pole
// is +z, so the sums are taken in a frame whose z is the image's pole and the
// coefficients rotated back with the (exact, block-diagonal) SH rotation.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <vector>

#include "prt/error.hpp"
#include "prt/sh.hpp"
#include "prt/sh_rotation.hpp"

namespace prt::sh {

Eigen::MatrixX3d project_equirect(int order, int width, int height, const float* rgb) {
  if (order <= 0) return Eigen::MatrixX3d(0, 3);
  if (width < 1 || height < 1) throw Error("equirectangular projection: empty image");
  const int n = coefficient_count(order);
  // Longitude of texel x, as DirectionSet::equirect: phi = 2 pi ((x + 0.5) / w - 0.5);
  // the (right-handed) pole frame below sees azimuth -phi.
  Eigen::MatrixXd cos_table(order, width), sin_table(order, width);
  for (int x = 0; x < width; ++x) {
    const double phi = -2.0 * M_PI * ((x + 0.5) / width - 0.5);
    for (int m = 0; m < order; ++m) {
      cos_table(m, x) = std::cos(m * phi);
      sin_table(m, x) = std::sin(m * phi);
    }
  }
  const double dphi = 2.0 * M_PI / width;
  constexpr int kRows = 8;
  const int blocks = (height + kRows - 1) / kRows;
  std::vector<Eigen::MatrixX3d> partial(blocks);
  tbb::parallel_for(0, blocks, [&](int b) {
    Eigen::MatrixX3d sum = Eigen::MatrixX3d::Zero(n, 3);
    Eigen::Matrix<double, Eigen::Dynamic, 3> row(width, 3);
    std::vector<double> legendre(n);
    for (int y = b * kRows; y < std::min(height, (b + 1) * kRows); ++y) {
      // Exact solid angle of the row, as DirectionSet::equirect.
      const double theta = M_PI * (y + 0.5) / height;
      const double weight =
          dphi * (std::cos(M_PI * y / height) - std::cos(M_PI * (y + 1) / height));
      for (int x = 0; x < width; ++x)
        for (int c = 0; c < 3; ++c) row(x, c) = rgb[(std::size_t(y) * width + x) * 3 + c];
      const Eigen::MatrixX3d cos_sums = cos_table * row, sin_sums = sin_table * row;
      // y_lm at longitude 0 of the pole frame: its normalised Legendre part
      // (cos(0) = 1), the sqrt(2) of m != 0 included.
      evaluate(order, std::sin(theta), 0.0, std::cos(theta), legendre.data());
      for (int l = 0; l < order; ++l) {
        sum.row(index(l, 0)) += weight * legendre[index(l, 0)] * cos_sums.row(0);
        for (int m = 1; m <= l; ++m) {
          const double p = weight * legendre[index(l, m)];
          sum.row(index(l, m)) += p * cos_sums.row(m);
          sum.row(index(l, -m)) += p * sin_sums.row(m);
        }
      }
    }
    partial[b] = sum;
  });
  Eigen::MatrixXd pole_frame = Eigen::MatrixXd::Zero(n, 3);
  for (const auto& p : partial) pole_frame += p;  // fixed order: deterministic
  // Pole frame (x', y', z') = world (-z, -x, y): equirect_direction is
  // (sin t sin p, cos t, -sin t cos p) = (sin t cos(-p), sin t sin(-p), cos t)
  // in it. `frame` maps pole-frame directions to world ones (a rotation).
  Eigen::Matrix3d frame;
  frame << 0, -1, 0,  //
      0, 0, 1,        //
      -1, 0, 0;
  Eigen::MatrixXd world(n, 3);
  Rotation(order, frame).apply(pole_frame, world);
  return world;
}

}  // namespace prt::sh
