#include "prt/basis.hpp"

#include "prt/error.hpp"
#include "prt/mesh.hpp"

namespace prt {

std::shared_ptr<const RowParts> FitData::row_parts() const {
  if (parts) return parts;
  return single_part(mesh ? static_cast<Eigen::Index>(mesh->vertex_count()) : 0);
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
