// Per-cluster projection and assembly of the compressed form.
#include <tbb/parallel_for.h>

#include "prt/clustering.hpp"
#include "prt/error.hpp"
#include "prt/row_blocks.hpp"

namespace prt::clustering {

double approximation_error(RowsRef x, Eigen::Index p, const ClusterModel& model,
                           Eigen::Index components, ErrorScratch& scratch) {
  const Eigen::Index c =
      components < 0 ? model.basis.rows() : std::min(components, model.basis.rows());
  scratch.centred.noalias() = x.row(p).cast<double>() - model.mean;
  double error = scratch.centred.squaredNorm();
  if (c > 0) {
    scratch.projections.noalias() = model.basis.topRows(c) * scratch.centred.transpose();
    error -= scratch.projections.squaredNorm();
  }
  return std::max(error, 0.0);
}

double approximation_error(RowsRef x, Eigen::Index p, const ClusterModel& model,
                           Eigen::Index components) {
  ErrorScratch scratch;
  return approximation_error(x, p, model, components, scratch);
}

CompressedTransfer assemble(const Rows& rows, const std::vector<std::int32_t>& labels,
                            const std::vector<ClusterModel>& models, const std::string& name) {
  const auto& x = rows.x;
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
  for_each_row_block(
      Eigen::Index(0), x.rows(), Eigen::Index(1024), [&](Eigen::Index begin, Eigen::Index end) {
        for (Eigen::Index p = begin; p < end; ++p) {
          const ClusterModel& model = models[labels[p]];
          if (model.basis.rows() == 0) continue;
          const Eigen::RowVectorXd d = x.row(p).cast<double>() - model.mean;
          c.weights.row(p).head(model.basis.rows()) = (d * model.basis.transpose()).cast<float>();
        }
        rows.release(begin, end);
      });
  return c;
}

}  // namespace prt::clustering
