#include "prt/basis_metric.hpp"

#include <cxxabi.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <typeinfo>

#include "prt/basis.hpp"
#include "prt/error.hpp"
#include "prt/hemisphere.hpp"
#include "prt/log.hpp"
#include "prt/quadrature.hpp"

namespace prt {

// The interface's default projection (prt/basis.hpp) lives with the metric it
// needs, so the interface layer does not include the numerics layer.
Eigen::MatrixXd Basis::projection_matrix(const DirectionSet& set) const {
  Eigen::MatrixXd inner_products = set.weights.asDiagonal() * evaluate(set.directions);
  if (orthonormal()) return inner_products;  // G = I: bit for bit the quadrature
  // Least-squares coefficients through the dual basis: c = G^-1 int f B.
  return inner_products * basis_metric(*this).inverse;
}

DirectionSet metric_rule(const Basis& basis) {
  if (auto native = basis.native_directions()) return *native;
  return basis.domain() == Domain::hemisphere ? hemisphere::upper_quadrature(64)
                                              : gauss_product_sphere(64);
}

Eigen::MatrixXd gram_matrix(const Basis& basis) {
  const DirectionSet rule = metric_rule(basis);
  const Eigen::MatrixXd values = basis.evaluate(rule.directions);
  Eigen::MatrixXd gram = values.transpose() * rule.weights.asDiagonal() * values;
  return 0.5 * (gram + gram.transpose());  // exactly symmetric for the eigensolver
}

namespace {

// "a basis of 25 functions (CosineLobes)": what a message can say of a basis.
std::string label_of(const Basis& basis) {
  int status = 0;
  char* name = abi::__cxa_demangle(typeid(basis).name(), nullptr, nullptr, &status);
  std::string label = "a basis of " + std::to_string(basis.size()) + " functions";
  if (status == 0 && name) label += std::string(" (") + name + ")";
  std::free(name);
  return label;
}

}  // namespace

BasisMetric basis_metric(const Basis& basis, double cutoff) {
  BasisMetric metric;
  if (basis.orthonormal()) return metric;
  metric.identity = false;
  metric.gram = gram_matrix(basis);
  if (!metric.gram.allFinite())
    throw Error(label_of(basis) + ": its Gram matrix is not finite (its values are not)");
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(metric.gram);
  const Eigen::VectorXd& values = eigen.eigenvalues();  // ascending
  const double largest = values.size() ? values.maxCoeff() : 0.0;
  if (!(largest > 0)) throw Error(label_of(basis) + ": its Gram matrix is zero");
  Eigen::VectorXd inverted = Eigen::VectorXd::Zero(values.size());
  double smallest_kept = largest;
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    if (values[i] > cutoff * largest) {
      inverted[i] = 1.0 / values[i];
      smallest_kept = std::min(smallest_kept, values[i]);
    } else {
      ++metric.discarded;
    }
  }
  metric.inverse = eigen.eigenvectors() * inverted.asDiagonal() * eigen.eigenvectors().transpose();
  metric.condition = largest / smallest_kept;
  char text[300];
  if (metric.discarded > 0) {
    std::snprintf(text, sizeof text,
                  "its Gram matrix is rank-deficient: %d of %d eigenvalues below %g x the largest "
                  "were discarded (least squares in the span of the others)",
                  metric.discarded, int(values.size()), cutoff);
    log_warning_once(label_of(basis) + ": " + text);
  } else if (metric.condition > kMetricWarnCondition) {
    std::snprintf(text, sizeof text,
                  "its Gram matrix has condition number %.3g: least-squares coefficients and "
                  "relighting lose about %.0f of their ~16 digits",
                  metric.condition, std::log10(metric.condition));
    log_warning_once(label_of(basis) + ": " + text);
  }
  return metric;
}

}  // namespace prt
