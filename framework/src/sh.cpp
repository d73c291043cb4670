#include "prt/sh.hpp"

#include <cmath>
#include <vector>

#include "prt/error.hpp"
#include "prt/quadrature.hpp"

namespace prt::sh {

void evaluate(int order, double x, double y, double z, double* out) {
  if (order <= 0) return;
  // q(l, m) = normalised P_l^m(z) / sin^m(theta); cos/sin(m phi) sin^m = Re/Im (x + iy)^m.
  constexpr double inv_sqrt_4pi = 0.28209479177387814347;  // 1 / sqrt(4 pi)
  constexpr double sqrt2 = 1.41421356237309504880;
  double q_mm = inv_sqrt_4pi;  // q(m, m)
  double c = 1.0, s = 0.0;     // Re, Im of (x + iy)^m
  for (int m = 0; m < order; ++m) {
    if (m > 0) {
      q_mm *= std::sqrt((2.0 * m + 1.0) / (2.0 * m));
      const double c_next = c * x - s * y;
      s = c * y + s * x;
      c = c_next;
    }
    const double scale_cos = m == 0 ? 1.0 : sqrt2 * c;
    const double scale_sin = sqrt2 * s;
    // Upward recurrence in l at fixed m.
    double q_prev = 0.0, q = q_mm;
    for (int l = m; l < order; ++l) {
      if (l == m + 1) {
        q_prev = q;
        q = std::sqrt(2.0 * m + 3.0) * z * q_mm;
      } else if (l > m + 1) {
        const double ll = l, mm = m;
        const double a = std::sqrt((4.0 * ll * ll - 1.0) / (ll * ll - mm * mm));
        const double b =
            std::sqrt(((ll - 1.0) * (ll - 1.0) - mm * mm) / (4.0 * (ll - 1.0) * (ll - 1.0) - 1.0));
        const double next = a * (z * q - b * q_prev);
        q_prev = q;
        q = next;
      }
      out[index(l, m)] = q * scale_cos;
      if (m > 0) out[index(l, -m)] = q * scale_sin;
    }
  }
}

Eigen::MatrixXd evaluate(int order, const Directions& directions) {
  const int n = coefficient_count(order);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> values(directions.rows(),
                                                                                n);
  for (Eigen::Index k = 0; k < directions.rows(); ++k)
    evaluate(order, directions(k, 0), directions(k, 1), directions(k, 2), values.row(k).data());
  return values;
}

namespace {

// Ivanic & Ruedenberg (1996, with the 1998 errata) for real SH without the
// Condon-Shortley phase; r1 is the l = 1 block in (y, z, x) order.
class BandRotator {
 public:
  BandRotator(const Eigen::Matrix3d& r1, int order) : order_(order), r1_(r1) {}

  double band1(int i, int j) const { return r1_(i + 1, j + 1); }

  // P^l_{i}(a, b) uses the previous band's block `prev` (indices in [-(l-1), l-1]).
  double P(int i, int a, int b, int l, const Eigen::MatrixXd& prev) const {
    auto R = [&](int m, int n) { return prev(m + l - 1, n + l - 1); };
    if (b == l) return band1(i, 1) * R(a, l - 1) - band1(i, -1) * R(a, -l + 1);
    if (b == -l) return band1(i, 1) * R(a, -l + 1) + band1(i, -1) * R(a, l - 1);
    return band1(i, 0) * R(a, b);
  }

  Eigen::MatrixXd next_band(int l, const Eigen::MatrixXd& prev) const {
    Eigen::MatrixXd block(2 * l + 1, 2 * l + 1);
    for (int m = -l; m <= l; ++m) {
      for (int n = -l; n <= l; ++n) {
        const double d = (m == 0) ? 1.0 : 0.0;
        const double denominator =
            (std::abs(n) < l) ? double((l + n) * (l - n)) : double((2 * l) * (2 * l - 1));
        const int am = std::abs(m);
        const double u = std::sqrt(double((l + m) * (l - m)) / denominator);
        const double v = 0.5 *
                         std::sqrt((1.0 + d) * double((l + am - 1) * (l + am)) / denominator) *
                         (1.0 - 2.0 * d);
        const double w =
            -0.5 * std::sqrt(double((l - am - 1) * (l - am)) / denominator) * (1.0 - d);
        double value = 0.0;
        if (u != 0.0) value += u * P(0, m, n, l, prev);
        if (v != 0.0) value += v * V(m, n, l, prev);
        if (w != 0.0) value += w * W(m, n, l, prev);
        block(m + l, n + l) = value;
      }
    }
    return block;
  }

 private:
  double V(int m, int n, int l, const Eigen::MatrixXd& prev) const {
    if (m == 0) return P(1, 1, n, l, prev) + P(-1, -1, n, l, prev);
    if (m > 0) {
      const double d = (m == 1) ? 1.0 : 0.0;
      return P(1, m - 1, n, l, prev) * std::sqrt(1.0 + d) - P(-1, -m + 1, n, l, prev) * (1.0 - d);
    }
    const double d = (m == -1) ? 1.0 : 0.0;
    return P(1, m + 1, n, l, prev) * (1.0 - d) + P(-1, -m - 1, n, l, prev) * std::sqrt(1.0 + d);
  }
  double W(int m, int n, int l, const Eigen::MatrixXd& prev) const {
    if (m > 0) return P(1, m + 1, n, l, prev) + P(-1, -m - 1, n, l, prev);
    return P(1, m - 1, n, l, prev) - P(-1, -m + 1, n, l, prev);
  }

  int order_;
  Eigen::Matrix3d r1_;
};

}  // namespace

Eigen::MatrixXd rotation(int order, const Eigen::Matrix3d& r) {
  const int n = coefficient_count(order);
  Eigen::MatrixXd result = Eigen::MatrixXd::Zero(n, n);
  if (order <= 0) return result;
  result(0, 0) = 1.0;
  if (order == 1) return result;
  // The l = 1 block: coefficients transform like (y, z, x).
  static const int perm[3] = {1, 2, 0};
  Eigen::Matrix3d r1;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r1(i, j) = r(perm[i], perm[j]);
  BandRotator rotator(r1, order);
  Eigen::MatrixXd block = r1;
  result.block(1, 1, 3, 3) = r1;
  for (int l = 2; l < order; ++l) {
    block = rotator.next_band(l, block);
    result.block(l * l, l * l, 2 * l + 1, 2 * l + 1) = block;
  }
  return result;
}

Eigen::VectorXd clamped_cosine_zonal(int order) {
  // z_l = 2 pi sqrt((2l+1)/(4 pi)) int_0^1 P_l(t) t dt; the integrand is a
  // polynomial, so Gauss-Legendre quadrature on [0, 1] is exact.
  Eigen::VectorXd z = Eigen::VectorXd::Zero(std::max(order, 0));
  const GaussLegendre rule = gauss_legendre(order / 2 + 2);
  for (std::size_t i = 0; i < rule.nodes.size(); ++i) {
    const double t = 0.5 * (rule.nodes[i] + 1.0), weight = 0.5 * rule.weights[i];
    double p_prev = 0.0, p = 1.0;  // P_{l-1}(t), P_l(t)
    for (int l = 0; l < order; ++l) {
      z[l] += weight * p * t;
      const double p_next = ((2.0 * l + 1.0) * t * p - l * p_prev) / (l + 1.0);
      p_prev = p;
      p = p_next;
    }
  }
  for (int l = 0; l < order; ++l) z[l] *= 2.0 * M_PI * std::sqrt((2.0 * l + 1.0) / (4.0 * M_PI));
  return z;
}

Eigen::VectorXd clamped_cosine(int order, const Eigen::Vector3d& normal) {
  const Eigen::VectorXd z = clamped_cosine_zonal(order);
  Eigen::VectorXd y(coefficient_count(order));
  const Eigen::Vector3d n = normal.normalized();
  evaluate(order, n.x(), n.y(), n.z(), y.data());
  for (int l = 0; l < order; ++l)
    for (int m = -l; m <= l; ++m) y[index(l, m)] *= std::sqrt(4.0 * M_PI / (2.0 * l + 1.0)) * z[l];
  return y;
}

Eigen::VectorXd window(int order, const std::string& kind) {
  if (kind != "none" && kind != "hanning" && kind != "lanczos")
    throw Error("unknown SH window \"" + kind + "\"; valid: none, hanning, lanczos");
  Eigen::VectorXd factors(coefficient_count(order));
  for (int l = 0; l < order; ++l) {
    const double x = double(l) / order;
    double sigma = 1.0;
    if (kind == "hanning") sigma = 0.5 * (1.0 + std::cos(M_PI * x));
    if (kind == "lanczos" && l > 0) sigma = std::sin(M_PI * x) / (M_PI * x);
    for (int m = -l; m <= l; ++m) factors[index(l, m)] = sigma;
  }
  return factors;
}

}  // namespace prt::sh
