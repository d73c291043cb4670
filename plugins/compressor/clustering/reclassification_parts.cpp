// Reclassification (reclassification.cpp) in a run of several parts (prt-mpi
// ranks). Its greedy order is global: a move changes the candidates of the
// moved vertex's neighbours, wherever they lie. So the first part runs it as
// one process would, on every row gathered in row order, and the parts then
// take back their rows that changed. The result is the serial run's, bit for
// bit: the same rows, the same compressed form (gather_rows), the same code.
//
// Communication, once per bake: every part sends its rows to the first
// (v x n floats in all), and the first broadcasts the changed rows (cluster
// id and n' weights of each vertex that moved: a few percent of v).
#include <cstring>

#include "prt/clustering.hpp"
#include "prt/row_gather.hpp"

namespace prt::clustering {

MatrixXfRow gather_signal(const Rows& rows) {
  return gather_float_rows(*rows.parts, rows.x, "reclassification");
}

namespace {

// Per changed vertex: its index, its cluster and its weights, as doubles
// (exact for int32 ids, vertex indices below 2^53 and floats).
std::vector<double> changed_rows(const std::vector<std::int32_t>& labels_before,
                                 const MatrixXfRow& weights_before, const CompressedTransfer& c) {
  std::vector<double> out;
  const Eigen::Index width = c.weights.cols();
  for (std::size_t p = 0; p < c.cluster_of_vertex.size(); ++p) {
    const auto row = static_cast<Eigen::Index>(p);
    const bool moved = c.cluster_of_vertex[p] != labels_before[p] ||
                       std::memcmp(c.weights.row(row).data(), weights_before.row(row).data(),
                                   std::size_t(width) * sizeof(float)) != 0;
    if (!moved) continue;
    out.push_back(double(p));
    out.push_back(double(c.cluster_of_vertex[p]));
    for (Eigen::Index j = 0; j < width; ++j) out.push_back(double(c.weights(row, j)));
  }
  return out;
}

}  // namespace

std::size_t reclassify(const Rows& rows, const Mesh& mesh, double error_budget,
                       CompressedTransfer& compressed) {
  if (!rows.distributed())
    return reclassify(rows.x, mesh, error_budget, compressed,
                      [&rows](Eigen::Index begin, Eigen::Index end) { rows.release(begin, end); });
  const MatrixXfRow whole = gather_signal(rows);
  rows.release_all();
  const Eigen::Index width = compressed.weights.cols();
  std::size_t moves = 0;
  std::vector<double> changed;
  if (rows.parts->first()) {  // the whole compressed form is here (gather_rows)
    const std::vector<std::int32_t> labels_before = compressed.cluster_of_vertex;
    const MatrixXfRow weights_before = compressed.weights;
    moves = reclassify(whole, mesh, error_budget, compressed);
    changed = changed_rows(labels_before, weights_before, compressed);
  }
  std::vector<char> bytes = to_bytes(changed);
  rows.parts->broadcast(bytes, 0);
  if (rows.parts->first()) return moves;
  changed = to_doubles(bytes);
  const Shard shard = rows.shard;
  const std::size_t stride = std::size_t(width) + 2;
  for (std::size_t at = 0; at + stride <= changed.size(); at += stride) {
    const auto p = static_cast<Eigen::Index>(changed[at]);
    if (p < shard.first || p >= shard.last) continue;
    const Eigen::Index local = p - shard.first;
    compressed.cluster_of_vertex[std::size_t(local)] = static_cast<std::int32_t>(changed[at + 1]);
    for (Eigen::Index j = 0; j < width; ++j)
      compressed.weights(local, j) = static_cast<float>(changed[at + 2 + std::size_t(j)]);
  }
  return moves;
}

}  // namespace prt::clustering
