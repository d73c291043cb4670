#include "prt/quadrature.hpp"

#include <cmath>

#include "prt/error.hpp"

namespace prt {

GaussLegendre gauss_legendre(int n) {
  if (n < 1) throw Error("gauss_legendre: need at least one node");
  GaussLegendre rule{std::vector<double>(n), std::vector<double>(n)};
  for (int i = 0; i < n; ++i) {
    // Newton iteration on P_n from the Tricomi initial guess.
    double x = std::cos(M_PI * (i + 0.75) / (n + 0.5));
    double derivative = 1.0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      double p0 = 1.0, p1 = x;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      if (n == 1) p0 = 1.0, p1 = x;
      derivative = n * (x * p1 - p0) / (x * x - 1.0);
      const double step = p1 / derivative;
      x -= step;
      if (std::abs(step) < 1e-16) break;
    }
    rule.nodes[i] = x;
    rule.weights[i] = 2.0 / ((1.0 - x * x) * derivative * derivative);
  }
  return rule;
}

DirectionSet gauss_product_sphere(int n) {
  const GaussLegendre rule = gauss_legendre(n);
  const int m = 2 * n;
  DirectionSet set{"gauss", Directions(n * m, 3), Eigen::VectorXd(n * m)};
  for (int i = 0; i < n; ++i) {
    const double z = rule.nodes[i], r = std::sqrt(std::max(0.0, 1.0 - z * z));
    for (int j = 0; j < m; ++j) {
      const double phi = 2.0 * M_PI * (j + 0.5) / m;
      const int k = i * m + j;
      set.directions.row(k) << r * std::cos(phi), r * std::sin(phi), z;
      set.weights[k] = rule.weights[i] * 2.0 * M_PI / m;
    }
  }
  return set;
}

}  // namespace prt
