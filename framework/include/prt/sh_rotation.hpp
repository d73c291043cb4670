// Rotation of real spherical-harmonic coefficients to high degree (l = 1000 and beyond).
//
// Convention: that of prt/sh.hpp (index l (l + 1) + m, orthonormal, no Condon-Shortley phase).
// The matrix of a rotation R maps the coefficients of f to those of g(d) = f(R^T d), as
// sh::rotation; it is block diagonal, one (2l + 1)^2 block per band, rows and columns ordered
// m = -l..l, so the l = 1 block is R in (y, z, x) order.
//
// Algorithm: R = Rz(alpha) Ry(beta) Rz(gamma) (ZYZ), with the angles taken from R's quaternion
// so that alpha + gamma stays exact near beta = 0 and alpha - gamma near beta = pi. The
// y-rotation comes from H^{m',m}_l(beta) = eps_{m'} eps_{-m} d^l_{m'm}(beta) (eps_k = (-1)^k for
// k > 0, else 1) by the recursion in m' of Gumerov & Duraiswami, "Recursive computation of
// spherical harmonic rotation coefficients of large degree" (2015, arXiv:1403.7698), seeded by
// Schmidt semi-normalised associated Legendre values of cos(beta). That recursion is stable to
// degrees in the thousands, unlike the Ivanic-Ruedenberg one (accurate to 1e-10 only to l ~ 70).
// Each real block entry is then a few flops from H and cos/sin(k alpha +- m gamma).
// Cost O(l^2) per band; storage sum (2l + 1)^2 = O(order^3).
#pragma once
#include <Eigen/Core>
#include <cstddef>
#include <vector>

namespace prt::sh {

// Rotation of real SH coefficients, stored block-diagonally: one (2l+1)^2 block per band.
class Rotation {
 public:
  using Block =
      Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;

  // g(d) = f(R^T d), same convention as sh::rotation. `rotation` should be a proper rotation;
  // small deviations from orthonormality are absorbed (it is used through its unit quaternion,
  // so the result is always exactly orthogonal). order <= 0 gives an empty rotation.
  Rotation(int order, const Eigen::Matrix3d& rotation);

  int order() const { return order_; }

  // Row-major (2l+1) x (2l+1) block of band l, 0 <= l < order (rows and columns m = -l..l).
  Block band(int l) const;

  // out = R in, for order^2 x k column-major coefficient matrices (k channels, e.g. RGB as
  // k = 3); in and out may not alias.
  void apply(const Eigen::Ref<const Eigen::MatrixXd>& in, Eigen::Ref<Eigen::MatrixXd> out) const;

  // The order^2 x order^2 matrix, for callers that need it.
  Eigen::MatrixXd dense() const;

  // Offset of band l's block in the block storage: sum_{j < l} (2j + 1)^2.
  static std::size_t band_offset(int l) {
    const std::size_t n = l;
    return (4 * n * n * n - n) / 3;
  }

 private:
  int order_;
  std::vector<double> blocks_;
};

// Computes the (2l+1)^2 block of band l alone (row-major into `out`), so that very high bands can
// be checked one at a time without storing all lower bands (O(l^2) memory and time).
void rotation_band(int l, const Eigen::Matrix3d& rotation, double* out);

}  // namespace prt::sh
