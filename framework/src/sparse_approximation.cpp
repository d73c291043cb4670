// The non-linear approximation of a transfer in its own basis (Ng,
// Ramamoorthi and Hanrahan 2003, "All-Frequency Shadows Using Non-linear
// Wavelet Lighting Approximation", section 4: keep each vertex's k largest
// coefficients): what a basis with approximation_terms() (Haar's keep-k)
// stores instead of a compressor's encoding. The kept coefficients are a
// sparse CompressedTransfer (weight_index), relit like any other.
#include <algorithm>
#include <cmath>
#include <numeric>

#include "prt/row_blocks.hpp"
#include "prt/transfer.hpp"

namespace prt {

CompressedTransfer keep_largest(const TransferSignal& signal, int terms) {
  const Eigen::Index n = signal.dimension(), v = signal.vertices();
  const int k = static_cast<int>(std::min<Eigen::Index>(std::max(terms, 1), n));
  CompressedTransfer c;
  c.compressor = "largest-" + std::to_string(k);
  c.dimension = n;
  c.components = k;
  c.cluster_of_vertex.assign(v, 0);
  c.means = MatrixXfRow::Zero(1, n);
  c.representatives.push_back(MatrixXfRow(0, n));
  c.weights.resize(v, k);
  c.weight_index.resize(static_cast<std::size_t>(v) * k);
  const auto rows = signal.rows();
  for_each_row_block(Eigen::Index(0), v, Eigen::Index(4096), [&](Eigen::Index b, Eigen::Index e) {
    std::vector<std::int32_t> order(n);
    for (Eigen::Index p = b; p < e; ++p) {
      std::iota(order.begin(), order.end(), 0);
      const auto row = rows.row(p);
      std::partial_sort(order.begin(), order.begin() + k, order.end(), [&](int a, int b) {
        const float fa = std::abs(row[a]), fb = std::abs(row[b]);
        return fa != fb ? fa > fb : a < b;  // ties by index: deterministic
      });
      std::sort(order.begin(), order.begin() + k);  // ascending index: friendlier gathers
      for (int j = 0; j < k; ++j) {
        c.weight_index[p * k + j] = order[j];
        c.weights(p, j) = row[order[j]];
      }
    }
    signal.release(b, e);
  });
  return c;
}

}  // namespace prt
