#include "prt/rendered_metric.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "prt/basis.hpp"
#include "prt/basis_metric.hpp"
#include "prt/error.hpp"
#include "prt/row_blocks.hpp"

namespace prt {

namespace {

// F with F F^T = G and its inverse: the Cholesky factor, or for a G the
// metric's cut-off made rank-deficient, V sqrt(max(lambda, cutoff lambda_max))
// (the discarded directions keep a tiny weight, so F stays invertible).
void factor_metric(const Basis& basis, Eigen::MatrixXd& factor, Eigen::MatrixXd& inverse) {
  const BasisMetric metric = basis_metric(basis);
  if (metric.identity) return;
  const Eigen::LLT<Eigen::MatrixXd> cholesky(metric.gram);
  if (metric.discarded == 0 && cholesky.info() == Eigen::Success) {
    factor = cholesky.matrixL();
    inverse = cholesky.matrixL().solve(Eigen::MatrixXd::Identity(factor.rows(), factor.cols()));
    return;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(metric.gram);
  const double floor = kMetricCutoff * eigen.eigenvalues().maxCoeff();
  const Eigen::VectorXd root = eigen.eigenvalues().cwiseMax(floor).cwiseSqrt();
  factor = eigen.eigenvectors() * root.asDiagonal();
  inverse = root.cwiseInverse().asDiagonal() * eigen.eigenvectors().transpose();
}

}  // namespace

RenderedMetric::RenderedMetric(const Basis& light, const Basis* exit) {
  factor_metric(light, light_, light_inverse_);
  if (exit) factor_metric(*exit, exit_, exit_inverse_);
}

void RenderedMetric::apply(Eigen::Ref<Eigen::MatrixXd> rows, int exit_rows, bool forward) const {
  const Eigen::Index cols = rows.cols();
  const Eigen::Index light_size =
      light_.size() ? light_.rows() : (exit_.size() ? cols / exit_rows : cols);
  const Eigen::Index block = Eigen::Index(exit_rows) * light_size;
  if (block == 0 || cols % block != 0)
    throw Error("transfer rows of " + std::to_string(cols) + " values do not hold blocks of " +
                std::to_string(exit_rows) + " x " + std::to_string(light_size) +
                " (exit rows x light coefficients)");
  if (exit_.size() && exit_.rows() != exit_rows)
    throw Error("transfer rows hold " + std::to_string(exit_rows) +
                " exit rows, but the exit "
                "basis has " +
                std::to_string(exit_.rows()) + " functions");
  using Block = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  Block m(exit_rows, light_size);
  // Row by row, so that a row's result does not depend on which rows share
  // its block (core counts and ranks give the same bits).
  for (Eigen::Index p = 0; p < rows.rows(); ++p)
    for (Eigen::Index group = 0; group < cols / block; ++group) {
      for (int r = 0; r < exit_rows; ++r)
        m.row(r) = rows.row(p).segment(group * block + r * light_size, light_size);
      if (forward) {
        if (exit_.size()) m = (exit_.transpose() * m).eval();
        if (light_.size()) m = (m * light_).eval();
      } else {
        if (exit_.size()) m = (exit_inverse_.transpose() * m).eval();
        if (light_.size()) m = (m * light_inverse_).eval();
      }
      for (int r = 0; r < exit_rows; ++r)
        rows.row(p).segment(group * block + r * light_size, light_size) = m.row(r);
    }
}

void RenderedMetric::whiten_rows(Eigen::Ref<Eigen::MatrixXd> rows, int exit_rows) const {
  if (!identity()) apply(rows, exit_rows, true);
}

void RenderedMetric::unwhiten_rows(MatrixXfRow& rows, int exit_rows) const {
  if (identity() || rows.size() == 0) return;
  for_each_row_block(Eigen::Index(0), rows.rows(), Eigen::Index(256),
                     [&](Eigen::Index begin, Eigen::Index end) {
                       Eigen::MatrixXd block = rows.middleRows(begin, end - begin).cast<double>();
                       apply(block, exit_rows, false);
                       rows.middleRows(begin, end - begin) = block.cast<float>();
                     });
}

void RenderedMetric::unwhiten(CompressedTransfer& compressed, int exit_rows) const {
  if (identity()) return;
  if (compressed.sparse())
    throw Error(
        "a sparse approximation keeps a basis's own coefficients; it cannot be mapped "
        "out of the rendered metric");
  unwhiten_rows(compressed.means, exit_rows);
  for (MatrixXfRow& representatives : compressed.representatives)
    unwhiten_rows(representatives, exit_rows);
}

TransferSignal RenderedMetric::whiten(const TransferSignal& signal) const {
  return map_row_blocks(signal, Eigen::Index(256), [&](Eigen::Ref<const MatrixXfRow> rows) {
    Eigen::MatrixXd block = rows.cast<double>();
    whiten_rows(block, signal.exit_rows);
    return MatrixXfRow(block.cast<float>());
  });
}

CompressedTransfer encode_in_metric(const Compressor& compressor, const TransferSignal& signal,
                                    const Mesh* mesh, const Distribution& where,
                                    const RenderedMetric& metric) {
  if (metric.identity() || compressor.exact()) return compressor.encode_shard(signal, mesh, where);
  const TransferSignal whitened = metric.whiten(signal);
  CompressedTransfer compressed = compressor.encode_shard(whitened, mesh, where);
  metric.unwhiten(compressed, signal.exit_rows);
  return compressed;
}

}  // namespace prt
