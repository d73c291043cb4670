// Sums over the rows of a (possibly distributed) signal: per-cluster sums,
// counts and scatter matrices, through segment_sum's fixed tree.
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <cstring>

#include "prt/clustering.hpp"
#include "prt/compressor.hpp"
#include "prt/error.hpp"
#include "prt/progress.hpp"
#include "prt/segment_sum.hpp"

namespace prt::clustering {

Rows::Rows(const MatrixXfRow& x) : x(x), shard(whole(x.rows())), comm(solo()) {}

Rows::Rows(const MatrixXfRow& local, const Shard& shard, const Communicator& comm)
    : x(local), shard(shard), comm(comm) {
  if (local.rows() != shard.rows())
    throw Error("clustering: " + std::to_string(local.rows()) + " local rows for a shard of " +
                std::to_string(shard.rows()));
}

std::pair<Eigen::Index, Eigen::Index> Rows::segment_rows(Eigen::Index segment) const {
  return {segment_begin(segment) - shard.first, segment_end(segment, shard.total) - shard.first};
}

double Rows::sum(const std::vector<double>& per_row) const {
  return segment_sum_rows(shard, per_row, comm);
}

Eigen::RowVectorXd Rows::fetch(Eigen::Index global) const {
  if (!distributed()) return x.row(global).cast<double>();
  int owner = 0;
  while (owner + 1 < comm.size() && shard_of(shard.total, owner, comm.size()).last <= global)
    ++owner;
  std::vector<double> values;
  if (owner == comm.rank()) {
    const Eigen::RowVectorXd row = x.row(global - shard.first).cast<double>();
    values.assign(row.data(), row.data() + row.size());
  }
  std::vector<char> bytes = to_bytes(values);
  comm.broadcast(bytes, owner);
  const std::vector<double> row = to_doubles(bytes);
  return Eigen::Map<const Eigen::RowVectorXd>(row.data(), static_cast<Eigen::Index>(row.size()));
}

bool Rows::any(bool mine) const {
  if (!distributed()) return mine;
  for (const auto& flag : allgather(comm, {mine ? 1.0 : 0.0}))
    if (flag[0] != 0) return true;
  return false;
}

ClusterSums cluster_sums(const Rows& rows, const std::vector<std::int32_t>& labels, int k) {
  const Eigen::Index n = rows.cols();
  const auto total = segment_sum(
      rows.shard,
      [&](Eigen::Index s) {
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
        return out;
      },
      rows.comm);
  ClusterSums result{RowMatrixXd::Zero(k, n), std::vector<double>(k, 0.0)};
  if (total.empty()) return result;
  result.sums = Eigen::Map<const RowMatrixXd>(total.data(), k, n);
  result.counts.assign(total.begin() + std::ptrdiff_t(k) * n, total.end());
  return result;
}

namespace {

// Scatter sum_p (x_p - m)(x_p - m)^T of each cluster in `which` (lower
// triangles): a block per cluster, only for the clusters a segment touches,
// in passes over groups of clusters whose blocks stay within kGroupBytes
// (the tree holds a few partials per thread at once).
constexpr std::size_t kGroupBytes = std::size_t(64) << 20;

std::vector<Eigen::MatrixXd> cluster_scatter(const Rows& rows,
                                             const std::vector<std::int32_t>& labels,
                                             const RowMatrixXd& means,
                                             const std::vector<int>& which) {
  const Eigen::Index n = rows.cols();
  // Every rank receives every rank's subtree roots: the bound is shared.
  const std::size_t group =
      std::max<std::size_t>(1, kGroupBytes / std::size_t(rows.comm.size()) /
                                   (sizeof(double) * std::size_t(n) * std::size_t(n)));
  Blocks total;
  std::vector<bool> wanted(static_cast<std::size_t>(means.rows()), false);
  for (std::size_t start = 0; start < which.size(); start += group) {
    std::fill(wanted.begin(), wanted.end(), false);
    for (std::size_t i = start; i < std::min(which.size(), start + group); ++i)
      wanted[std::size_t(which[i])] = true;
    Blocks part = segment_sum_blocks(
        rows.shard,
        [&](Eigen::Index s) {
          const auto [begin, end] = rows.segment_rows(s);
          std::map<std::int32_t, std::vector<Eigen::Index>> members;
          for (Eigen::Index p = begin; p < end; ++p) {
            const std::int32_t l = labels[std::size_t(p)];
            if (l >= 0 && wanted[std::size_t(l)]) members[l].push_back(p);
          }
          Blocks out;
          Eigen::MatrixXd centred, sum;
          for (const auto& [cluster, list] : members) {
            centred.resize(n, static_cast<Eigen::Index>(list.size()));
            for (std::size_t j = 0; j < list.size(); ++j)
              centred.col(Eigen::Index(j)) =
                  (rows.x.row(list[j]).cast<double>() - means.row(cluster)).transpose();
            sum.setZero(n, n);
            sum.selfadjointView<Eigen::Lower>().rankUpdate(centred);
            // The lower triangle, column by column: half the bytes to add and send.
            std::vector<double>& block = out[cluster];
            block.resize(std::size_t(n * (n + 1) / 2));
            std::size_t at = 0;
            for (Eigen::Index c = 0; c < n; ++c)
              for (Eigen::Index r = c; r < n; ++r) block[at++] = sum(r, c);
          }
          return out;
        },
        rows.comm);
    total.merge(part);
  }
  std::vector<Eigen::MatrixXd> scatter(which.size());
  for (std::size_t i = 0; i < which.size(); ++i) {
    Eigen::MatrixXd& m = scatter[i];
    const auto it = total.find(which[i]);
    m = Eigen::MatrixXd::Zero(n, n);
    if (it == total.end()) continue;
    std::size_t at = 0;
    for (Eigen::Index c = 0; c < n; ++c)
      for (Eigen::Index r = c; r < n; ++r) m(r, c) = m(c, r) = it->second[at++];
  }
  return scatter;
}

// The principal directions of one cluster from its scatter.
void principal_directions(const Eigen::MatrixXd& scatter, ClusterModel& model) {
  const Eigen::Index c = model.basis.rows();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(scatter);
  const Eigen::VectorXd& values = solver.eigenvalues();  // ascending
  const double largest = std::max(values.size() ? values[values.size() - 1] : 0.0, 0.0);
  const double cutoff = std::max(largest * 1e-12, 1e-300);
  for (Eigen::Index i = 0; i < c && i < values.size(); ++i) {
    const Eigen::Index column = values.size() - 1 - i;
    const double lambda = values[column];
    if (!(lambda > cutoff)) break;  // rank reached: the rest stay zero
    const Eigen::RowVectorXd direction = solver.eigenvectors().col(column).transpose();
    const double norm = direction.norm();
    if (!(norm > 0) || !std::isfinite(norm)) break;
    model.basis.row(i) = direction / norm;
    model.eigenvalues[i] = lambda;
  }
}

}  // namespace

std::vector<ClusterModel> fit_models(const Rows& rows, const std::vector<std::int32_t>& labels,
                                     int k, const std::vector<int>& components,
                                     std::vector<double>* counts) {
  const Eigen::Index n = rows.cols();
  const ClusterSums sums = cluster_sums(rows, labels, k);
  std::vector<ClusterModel> models(static_cast<std::size_t>(k));
  RowMatrixXd means = RowMatrixXd::Zero(k, n);
  std::vector<int> which;
  for (int j = 0; j < k; ++j) {
    const int c = std::max(0, components[std::size_t(j)]);
    models[std::size_t(j)] = {Eigen::RowVectorXd::Zero(n), RowMatrixXd::Zero(c, n),
                              Eigen::VectorXd::Zero(c)};
    if (sums.counts[std::size_t(j)] == 0) continue;
    means.row(j) = sums.sums.row(j) / sums.counts[std::size_t(j)];
    models[std::size_t(j)].mean = means.row(j);
    if (c > 0) which.push_back(j);
  }
  const std::vector<Eigen::MatrixXd> scatter = cluster_scatter(rows, labels, means, which);
  // Each rank solves every size-th cluster and the ranks share the results
  // (the same solver on the same scatter gives the same bits anywhere).
  const int rank = rows.comm.rank(), ranks = rows.comm.size();
  tbb::parallel_for(std::size_t(0), which.size(), [&](std::size_t i) {
    Progress::check_interrupt();  // one eigen-solve may take seconds (glossy rows)
    if (int(i % std::size_t(ranks)) == rank)
      principal_directions(scatter[i], models[std::size_t(which[i])]);
  });
  if (ranks > 1) {
    std::vector<double> mine;
    for (std::size_t i = std::size_t(rank); i < which.size(); i += std::size_t(ranks)) {
      const ClusterModel& m = models[std::size_t(which[i])];
      mine.insert(mine.end(), m.basis.data(), m.basis.data() + m.basis.size());
      mine.insert(mine.end(), m.eigenvalues.data(), m.eigenvalues.data() + m.eigenvalues.size());
    }
    const auto all = allgather(rows.comm, mine);
    for (int r = 0; r < ranks; ++r) {
      std::size_t at = 0;
      for (std::size_t i = std::size_t(r); i < which.size(); i += std::size_t(ranks)) {
        ClusterModel& m = models[std::size_t(which[i])];
        const std::size_t size = std::size_t(m.basis.size()),
                          values = std::size_t(m.eigenvalues.size());
        if (at + size + values > all[std::size_t(r)].size())
          throw Error("clustering: rank " + std::to_string(r) + " sent too few model values");
        std::copy_n(&all[std::size_t(r)][at], size, m.basis.data());
        std::copy_n(&all[std::size_t(r)][at + size], values, m.eigenvalues.data());
        at += size + values;
      }
    }
  }
  if (counts) *counts = sums.counts;
  return models;
}

ClusterModel fit_cluster(const MatrixXfRow& x, const std::vector<std::uint32_t>& members,
                         int components) {
  std::vector<std::int32_t> labels(static_cast<std::size_t>(x.rows()), -1);
  for (std::uint32_t p : members) labels[p] = 0;
  return fit_models(Rows(x), labels, 1, {components}).front();
}

void gather_rows(const Rows& rows, CompressedTransfer& c) {
  gather_rows(Distribution{&rows.comm, rows.shard}, c);
}

}  // namespace prt::clustering
