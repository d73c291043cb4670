#include "prt/basis.hpp"

#include "prt/basis_metric.hpp"
#include "prt/error.hpp"
#include "prt/mesh.hpp"

namespace prt {

Shard FitData::rows() const {
  if (shard.total != 0) return shard;
  return whole(mesh ? static_cast<Eigen::Index>(mesh->vertex_count()) : 0);
}

Eigen::MatrixXd Basis::projection_matrix(const DirectionSet& set) const {
  Eigen::MatrixXd inner_products = set.weights.asDiagonal() * evaluate(set.directions);
  if (orthonormal()) return inner_products;  // G = I: bit for bit the quadrature
  // Least-squares coefficients through the dual basis: c = G^-1 int f B.
  return inner_products * basis_metric(*this).inverse;
}

Eigen::MatrixXd Basis::project(const Eigen::MatrixXd& samples, const DirectionSet& set) const {
  if (samples.cols() != set.size())
    throw Error("project: " + std::to_string(samples.cols()) + " samples per function for " +
                std::to_string(set.size()) + " directions");
  return samples * projection_matrix(set);
}

Eigen::MatrixXd Basis::rotation_matrix(const Eigen::Matrix3d&) const {
  throw Error("this basis cannot rotate coefficient vectors; re-project the rotated light instead");
}

}  // namespace prt
