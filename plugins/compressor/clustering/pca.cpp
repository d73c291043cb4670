// Per-cluster PCA and assembly of the compressed form.
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>

#include "prt/clustering.hpp"
#include "prt/error.hpp"

namespace prt::clustering {

ClusterModel fit_cluster(const MatrixXfRow& x, const std::vector<std::uint32_t>& members,
                         int components) {
  const Eigen::Index n = x.cols(), m = static_cast<Eigen::Index>(members.size());
  const int c = std::max(0, components);
  ClusterModel model{Eigen::RowVectorXd::Zero(n), RowMatrixXd::Zero(c, n),
                     Eigen::VectorXd::Zero(c)};
  if (m == 0) return model;
  RowMatrixXd centred(m, n);
  for (Eigen::Index j = 0; j < m; ++j) centred.row(j) = x.row(members[j]).cast<double>();
  model.mean = centred.colwise().mean();
  centred.rowwise() -= model.mean;
  if (c == 0) return model;

  // The smaller of the two Gram matrices has the same non-zero spectrum.
  const bool small_side = m < n;
  const Eigen::MatrixXd gram = small_side ? Eigen::MatrixXd(centred * centred.transpose())
                                          : Eigen::MatrixXd(centred.transpose() * centred);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(gram);
  const Eigen::VectorXd& values = solver.eigenvalues();  // ascending
  const double largest = std::max(values.size() ? values[values.size() - 1] : 0.0, 0.0);
  const double cutoff = std::max(largest * 1e-12, 1e-300);
  for (int i = 0; i < c && i < values.size(); ++i) {
    const Eigen::Index column = values.size() - 1 - i;
    const double lambda = values[column];
    if (!(lambda > cutoff)) break;  // rank reached: the rest stay zero
    Eigen::RowVectorXd direction;
    if (small_side) {
      direction = (centred.transpose() * solver.eigenvectors().col(column)).transpose();
      direction /= std::sqrt(lambda);
    } else {
      direction = solver.eigenvectors().col(column).transpose();
    }
    const double norm = direction.norm();
    if (!(norm > 0) || !std::isfinite(norm)) break;
    model.basis.row(i) = direction / norm;
    model.eigenvalues[i] = lambda;
  }
  return model;
}

double approximation_error(const MatrixXfRow& x, Eigen::Index p, const ClusterModel& model) {
  const Eigen::RowVectorXd d = x.row(p).cast<double>() - model.mean;
  double error = d.squaredNorm();
  if (model.basis.rows() > 0) error -= (model.basis * d.transpose()).squaredNorm();
  return std::max(error, 0.0);
}

CompressedTransfer assemble(const MatrixXfRow& x, const std::vector<std::int32_t>& labels,
                            const std::vector<ClusterModel>& models, const std::string& name) {
  CompressedTransfer c;
  c.compressor = name;
  c.dimension = x.cols();
  c.cluster_of_vertex = labels;
  int components = 0;
  for (const auto& model : models) components = std::max<int>(components, model.basis.rows());
  c.components = components;
  c.means.resize(static_cast<Eigen::Index>(models.size()), x.cols());
  for (std::size_t k = 0; k < models.size(); ++k) {
    c.means.row(k) = models[k].mean.cast<float>();
    c.representatives.push_back(models[k].basis.cast<float>());
  }
  c.weights = MatrixXfRow::Zero(x.rows(), components);
  tbb::parallel_for(Eigen::Index(0), x.rows(), [&](Eigen::Index p) {
    const ClusterModel& model = models[labels[p]];
    if (model.basis.rows() == 0) return;
    const Eigen::RowVectorXd d = x.row(p).cast<double>() - model.mean;
    c.weights.row(p).head(model.basis.rows()) = (d * model.basis.transpose()).cast<float>();
  });
  return c;
}

}  // namespace prt::clustering
