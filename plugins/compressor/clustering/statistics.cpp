// Sums over the rows of a (possibly distributed) signal: per-cluster sums,
// counts and scatter matrices, through the run's parts (RowParts: a fixed tree).
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstring>
#include <tuple>

#include "lower_product.hpp"
#include "prt/clustering.hpp"
#include "prt/compressor.hpp"
#include "prt/error.hpp"
#include "prt/progress.hpp"
#include "prt/symmetric_eigen.hpp"

namespace prt::clustering {

Rows::Rows(RowsRef x)
    : x(x.data(), x.rows(), x.cols()), parts(single_part(x.rows())), shard(parts->shard()) {
  if (x.rows() > 1 && x.outerStride() != x.cols())
    throw Error("clustering: rows with a stride (a block of a wider matrix) are not contiguous");
}

Rows::Rows(const TransferSignal& signal)
    : x(signal.rows()),
      parts(single_part(signal.vertices())),
      shard(parts->shard()),
      signal(&signal) {}

Rows::Rows(const MatrixXfRow& local, std::shared_ptr<const RowParts> parts)
    : x(local.data(), local.rows(), local.cols()),
      parts(std::move(parts)),
      shard(this->parts->shard()) {
  if (local.rows() != shard.rows())
    throw Error("clustering: " + std::to_string(local.rows()) + " local rows for a shard of " +
                std::to_string(shard.rows()));
}

Rows::Rows(const TransferSignal& local, std::shared_ptr<const RowParts> parts)
    : x(local.rows()), parts(std::move(parts)), shard(this->parts->shard()), signal(&local) {
  if (local.vertices() != shard.rows())
    throw Error("clustering: " + std::to_string(local.vertices()) + " local rows for a shard of " +
                std::to_string(shard.rows()));
}

std::pair<Eigen::Index, Eigen::Index> Rows::segment_rows(Eigen::Index segment) const {
  return {segment_begin(segment) - shard.first, segment_end(segment, shard.total) - shard.first};
}

double Rows::sum(const std::vector<double>& per_row) const {
  return parts->sum_rows(per_row);
}

Eigen::RowVectorXd Rows::fetch(Eigen::Index global) const {
  if (!distributed()) return x.row(global).cast<double>();
  int owner = 0;
  while (owner + 1 < parts->count() && parts->shard_of(owner).last <= global) ++owner;
  std::vector<double> values;
  if (owner == parts->index()) {
    const Eigen::RowVectorXd row = x.row(global - shard.first).cast<double>();
    values.assign(row.data(), row.data() + row.size());
  }
  std::vector<char> bytes = to_bytes(values);
  parts->broadcast(bytes, owner);
  const std::vector<double> row = to_doubles(bytes);
  return Eigen::Map<const Eigen::RowVectorXd>(row.data(), static_cast<Eigen::Index>(row.size()));
}

bool Rows::any(bool mine) const {
  if (!distributed()) return mine;
  for (const auto& flag : parts->allgather({mine ? 1.0 : 0.0}))
    if (flag[0] != 0) return true;
  return false;
}

ClusterSums cluster_sums(const Rows& rows, const std::vector<std::int32_t>& labels, int k) {
  const Eigen::Index n = rows.cols();
  const auto total = rows.parts->sum([&](Eigen::Index s) {
    const auto [begin, end] = rows.segment_rows(s);
    std::vector<double> out(std::size_t(k) * (n + 1), 0.0);
    for (Eigen::Index p = begin; p < end; ++p) {
      const std::int32_t l = labels[std::size_t(p)];
      if (l < 0) continue;
      double* sum = &out[std::size_t(l) * n];
      const float* row = rows.x.row(p).data();
      for (Eigen::Index d = 0; d < n; ++d) sum[d] += double(row[d]);
      out[std::size_t(k) * n + l] += 1;
    }
    rows.release(begin, end);
    return out;
  });
  ClusterSums result{RowMatrixXd::Zero(k, n), std::vector<double>(k, 0.0)};
  if (total.empty()) return result;
  result.sums = Eigen::Map<const RowMatrixXd>(total.data(), k, n);
  result.counts.assign(total.begin() + std::ptrdiff_t(k) * n, total.end());
  return result;
}

std::vector<double> cluster_counts(const Rows& rows, const std::vector<std::int32_t>& labels,
                                   int k) {
  std::vector<double> total = rows.parts->sum([&](Eigen::Index s) {
    const auto [begin, end] = rows.segment_rows(s);
    std::vector<double> out(std::size_t(k), 0.0);
    for (Eigen::Index p = begin; p < end; ++p)
      if (labels[std::size_t(p)] >= 0) out[std::size_t(labels[std::size_t(p)])] += 1;
    return out;
  });
  if (total.empty()) total.assign(std::size_t(k), 0.0);
  return total;
}

std::vector<char> changed_clusters(const Rows& rows, const std::vector<std::int32_t>& before,
                                   const std::vector<std::int32_t>& after, int k) {
  std::vector<char> changed(std::size_t(k), 0);
  const auto mark = [&](std::int32_t l) {
    if (l >= 0 && l < k) changed[std::size_t(l)] = 1;
  };
  if (before.size() != after.size()) throw Error("clustering: labellings of different sizes");
  for (std::size_t p = 0; p < after.size(); ++p)
    if (before[p] != after[p]) mark(before[p]), mark(after[p]);
  if (!rows.distributed()) return changed;
  const std::vector<double> mine(changed.begin(), changed.end());
  for (const auto& theirs : rows.parts->allgather(mine))
    for (std::size_t j = 0; j < changed.size() && j < theirs.size(); ++j)
      if (theirs[j] != 0) changed[j] = 1;
  return changed;
}

ClusterModel fit_cluster(RowsRef x, const std::vector<std::uint32_t>& members, int components) {
  std::vector<std::int32_t> labels(static_cast<std::size_t>(x.rows()), -1);
  for (std::uint32_t p : members) labels[p] = 0;
  return fit_models(Rows(x), labels, 1, {components}).front();
}

void gather_rows(const Rows& rows, CompressedTransfer& c) {
  gather_rows(Distribution{rows.parts}, c);
}

}  // namespace prt::clustering
