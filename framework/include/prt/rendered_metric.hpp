// Transfer rows in the rendered metric (issue 39): coordinates in which the
// Euclidean norm of a row is the function-space norm of what it renders.
//
// A diffuse row t is the least-squares coefficients of a transfer function
// over the light domain: |T|^2 = t^T G_l t. A glossy row is M (exit x light,
// row-major) with exit radiance e = M G_l l: |M|^2 = tr(M^T G_e M G_l). With
// Cholesky factors G = L L^T both are Euclidean in M' = L_e^T M L_l, so a
// compressor that minimises |M' - M'~|^2 (every one of ours) minimises the
// error of what is rendered, over every unit light and view direction. The
// compressed form is mapped back (means and representatives times the inverse
// factors; weights and clusters unchanged), so renderers never see the
// whitened coordinates. Orthonormal bases have L = I: nothing is done.
#pragma once
#include <Eigen/Core>
#include <string>

#include "prt/compressor.hpp"
#include "prt/transfer.hpp"

namespace prt {

class Basis;

class RenderedMetric {
 public:
  RenderedMetric() = default;  // the identity: coefficient space is the rendered metric
  // `exit` is null for diffuse transfer.
  RenderedMetric(const Basis& light, const Basis* exit);

  bool identity() const { return light_.size() == 0 && exit_.size() == 0; }

  // Rows in whitened coordinates: M' = L_e^T M L_l per block of every row
  // (a copy; an on-disk signal is whitened into a row file beside its own).
  TransferSignal whiten(const TransferSignal& signal) const;
  // Rows mapped back in place: M = L_e^-T M' L_l^-1.
  void unwhiten_rows(MatrixXfRow& rows, int exit_rows) const;
  // A compressed form of whitened rows mapped back: means and representatives
  // (a sparse form's coefficients cannot be: refused).
  void unwhiten(CompressedTransfer& compressed, int exit_rows) const;
  // Rows whitened in place (double: the difference rows of measure()).
  void whiten_rows(Eigen::Ref<Eigen::MatrixXd> rows, int exit_rows) const;

 private:
  void apply(Eigen::Ref<Eigen::MatrixXd> rows, int exit_rows, bool forward) const;
  // Factors L (lower triangular, L L^T = G) and their inverses; empty: identity.
  Eigen::MatrixXd light_, light_inverse_, exit_, exit_inverse_;
};

// Encodes `signal` in the rendered metric: whitened, encoded, mapped back.
// The identity metric, an exact compressor or a sparse approximation encode
// the signal as it is.
CompressedTransfer encode_in_metric(const Compressor& compressor, const TransferSignal& signal,
                                    const Mesh* mesh, const Distribution& where,
                                    const RenderedMetric& metric);

}  // namespace prt
