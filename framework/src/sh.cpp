#include "prt/sh.hpp"

#include <cmath>
#include <vector>

#include "prt/error.hpp"
#include "prt/quadrature.hpp"
#include "prt/sh_rotation.hpp"

namespace prt::sh {

void evaluate(int order, double x, double y, double z, double* out) {
  if (order <= 0) return;
  // N(l, m) = normalised P_l^m(z), sin^m(theta) included: the sectoral seeds N(m, m) shrink
  // like sin^m while the degree recurrence stays O(1), so nothing overflows to l = 1000 and
  // beyond (values under the double range are genuinely negligible). cos/sin(m phi) come from
  // the unit vector (x, y) / sin(theta) by complex multiplication; at the poles, where every
  // m > 0 value is 0, phi = 0.
  constexpr double inv_sqrt_4pi = 0.28209479177387814347;  // 1 / sqrt(4 pi)
  constexpr double sqrt2 = 1.41421356237309504880;
  const double rho = std::hypot(x, y);  // sin(theta) for a unit direction
  const double c1 = rho > 0.0 ? x / rho : 1.0, s1 = rho > 0.0 ? y / rho : 0.0;
  double n_mm = inv_sqrt_4pi;  // N(m, m)
  double c = 1.0, s = 0.0;     // cos(m phi), sin(m phi)
  for (int m = 0; m < order; ++m) {
    if (m > 0) {
      n_mm *= std::sqrt((2.0 * m + 1.0) / (2.0 * m)) * rho;
      const double c_next = c * c1 - s * s1;
      s = s * c1 + c * s1;
      c = c_next;
    }
    const double scale_cos = m == 0 ? 1.0 : sqrt2 * c;
    const double scale_sin = sqrt2 * s;
    // Upward recurrence in l at fixed m.
    double n_prev = 0.0, n_l = n_mm;
    for (int l = m; l < order; ++l) {
      if (l == m + 1) {
        n_prev = n_l;
        n_l = std::sqrt(2.0 * m + 3.0) * z * n_mm;
      } else if (l > m + 1) {
        const double ll = l, mm = m;
        const double a = std::sqrt((4.0 * ll * ll - 1.0) / (ll * ll - mm * mm));
        const double b =
            std::sqrt(((ll - 1.0) * (ll - 1.0) - mm * mm) / (4.0 * (ll - 1.0) * (ll - 1.0) - 1.0));
        const double next = a * (z * n_l - b * n_prev);
        n_prev = n_l;
        n_l = next;
      }
      out[index(l, m)] = n_l * scale_cos;
      if (m > 0) out[index(l, -m)] = n_l * scale_sin;
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

Eigen::MatrixXd rotation(int order, const Eigen::Matrix3d& r) {
  if (order <= 0) return Eigen::MatrixXd::Zero(coefficient_count(order), coefficient_count(order));
  return Rotation(order, r).dense();
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
