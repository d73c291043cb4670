// CPCA's refit (Sloan et al. 2003, "Clustered Principal Components for
// Precomputed Radiance Transfer", section 4): every cluster's mean and its
// leading principal directions from its members, as each pass of iterative
// and adaptive CPCA needs (PCA is the case of one cluster). Each cluster is
// solved from its n x n scatter or, with fewer members than dimensions, its
// m x m Gram matrix, eight at a time in one batched eigen-solve; sums over
// rows go through the run's parts (RowParts::sum_blocks), and the ranks split the solves, so the
// bits are the same for any number of threads or ranks.
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

namespace {

// In a distributed run, the member rows of the clusters this rank fits from
// their members (`gathered`), in global row order, sent by the ranks that hold
// them (rank r's rows all precede rank r + 1's).
std::map<int, MatrixXfRow> gathered_rows(const Rows& rows,
                                         const std::vector<std::vector<std::uint32_t>>& members,
                                         const std::vector<int>& which,
                                         const std::vector<bool>& gathered,
                                         const std::vector<double>& counts) {
  const Eigen::Index n = rows.cols();
  const int rank = rows.parts->index(), ranks = rows.parts->count();
  std::map<int, MatrixXfRow> out;
  // Per root: every rank sends, for each gathered cluster the root solves,
  // its local member count and rows.
  for (int root = 0; root < ranks; ++root) {
    std::vector<char> mine;
    for (std::size_t i = std::size_t(root); i < which.size(); i += std::size_t(ranks)) {
      if (!gathered[i]) continue;
      const int cluster = which[i];
      const std::vector<std::uint32_t>& local = members[std::size_t(cluster)];
      const std::int64_t count = static_cast<std::int64_t>(local.size());
      const char* head = reinterpret_cast<const char*>(&count);
      mine.insert(mine.end(), head, head + sizeof count);
      for (std::uint32_t p : local) {
        const char* row = reinterpret_cast<const char*>(rows.x.row(p).data());
        mine.insert(mine.end(), row, row + sizeof(float) * std::size_t(n));
      }
    }
    const std::vector<std::vector<char>> parts = rows.parts->gather(mine, root);
    if (root != rank) continue;
    std::vector<std::size_t> read(std::size_t(ranks), 0);
    for (std::size_t i = std::size_t(root); i < which.size(); i += std::size_t(ranks)) {
      if (!gathered[i]) continue;
      MatrixXfRow& y = out[int(i)];
      y.resize(Eigen::Index(counts[std::size_t(which[i])]), n);
      Eigen::Index at = 0;
      for (int r = 0; r < ranks; ++r) {
        const std::vector<char>& part = parts[std::size_t(r)];
        std::size_t& from = read[std::size_t(r)];
        std::int64_t count = 0;
        if (from + sizeof count > part.size())
          throw Error("clustering: rank " + std::to_string(r) + " sent too few member rows");
        std::memcpy(&count, &part[from], sizeof count);
        from += sizeof count;
        const std::size_t bytes = std::size_t(count) * std::size_t(n) * sizeof(float);
        if (count < 0 || at + count > y.rows() || from + bytes > part.size())
          throw Error("clustering: rank " + std::to_string(r) + " sent a wrong member count");
        if (count > 0) std::memcpy(y.data() + at * n, &part[from], bytes);
        from += bytes;
        at += count;
      }
      if (at != y.rows()) throw Error("clustering: the ranks sent too few member rows");
    }
  }
  return out;
}

// Scatter sum_p (x_p - m)(x_p - m)^T of each cluster in `which` too large to
// gather (`gathered` false): a block per cluster, only for the clusters a
// segment touches, in passes over groups of clusters whose blocks stay within
// kGroupBytes (the tree holds a few partials per thread at once).
constexpr std::size_t kGroupBytes = std::size_t(64) << 20;

// The segment's rows [begin, end) of each wanted cluster, in row order:
// cluster j's are sorted[start[j], start[j + 1]) (a counting sort: a map of
// vectors per segment was most of the serial time of the scatter).
struct SegmentMembers {
  std::vector<std::size_t> start;
  std::vector<Eigen::Index> sorted;
};

SegmentMembers segment_members(const std::vector<std::int32_t>& labels,
                               const std::vector<bool>& wanted, Eigen::Index begin,
                               Eigen::Index end) {
  const std::size_t k = wanted.size();
  SegmentMembers m{std::vector<std::size_t>(k + 1, 0), {}};
  for (Eigen::Index p = begin; p < end; ++p) {
    const std::int32_t l = labels[std::size_t(p)];
    if (l >= 0 && wanted[std::size_t(l)]) ++m.start[std::size_t(l) + 1];
  }
  for (std::size_t j = 0; j < k; ++j) m.start[j + 1] += m.start[j];
  m.sorted.resize(m.start[k]);
  std::vector<std::size_t> next(m.start.begin(), m.start.end() - 1);
  for (Eigen::Index p = begin; p < end; ++p) {
    const std::int32_t l = labels[std::size_t(p)];
    if (l >= 0 && wanted[std::size_t(l)]) m.sorted[next[std::size_t(l)]++] = p;
  }
  return m;
}

struct ScatterScratch {
  Eigen::MatrixXd centred, sum;
};

// One cluster's scatter over `count` members, as its lower triangle column
// by column (half the bytes to add and send): one rank update of its members
// in row order, the same bits on any thread.
void lower_scatter(const Rows& rows, const Eigen::Index* members, std::size_t count,
                   const Eigen::RowVectorXd& mean, ScatterScratch& scratch,
                   std::vector<double>& block) {
  const Eigen::Index n = rows.cols();
  scratch.centred.resize(n, static_cast<Eigen::Index>(count));
  for (std::size_t j = 0; j < count; ++j)
    scratch.centred.col(Eigen::Index(j)) =
        (rows.x.row(members[j]).cast<double>() - mean).transpose();
  scratch.sum.setZero(n, n);
  scratch.sum.selfadjointView<Eigen::Lower>().rankUpdate(scratch.centred);
  block.resize(std::size_t(n * (n + 1) / 2));
  std::size_t at = 0;
  for (Eigen::Index c = 0; c < n; ++c)
    for (Eigen::Index r = c; r < n; ++r) block[at++] = scratch.sum(r, c);
}

// The blocks of one segment: the clusters of a segment run on every core, as
// a signal has few segments (5 for the bunny). The blocks are made first, so
// that the tasks only fill them.
Blocks segment_scatter(const Rows& rows, const std::vector<std::int32_t>& labels,
                       const RowMatrixXd& means, const std::vector<bool>& wanted, Eigen::Index s,
                       tbb::enumerable_thread_specific<ScatterScratch>& scratch) {
  const auto [begin, end] = rows.segment_rows(s);
  const SegmentMembers m = segment_members(labels, wanted, begin, end);
  Blocks out;
  struct Task {
    std::int32_t cluster;
    const Eigen::Index* members;
    std::size_t count;
    std::vector<double>* block;
  };
  std::vector<Task> tasks;
  for (std::size_t j = 0; j + 1 < m.start.size(); ++j)
    if (m.start[j + 1] > m.start[j])
      tasks.push_back({std::int32_t(j), &m.sorted[m.start[j]], m.start[j + 1] - m.start[j],
                       &out[std::int64_t(j)]});
  tbb::parallel_for(std::size_t(0), tasks.size(), [&](std::size_t i) {
    const Task& task = tasks[i];
    lower_scatter(rows, task.members, task.count, means.row(task.cluster), scratch.local(),
                  *task.block);
  });
  rows.release(begin, end);
  return out;
}

std::map<int, Eigen::MatrixXd> cluster_scatter(const Rows& rows,
                                               const std::vector<std::int32_t>& labels,
                                               const RowMatrixXd& means,
                                               const std::vector<int>& which,
                                               const std::vector<bool>& gathered) {
  const Eigen::Index n = rows.cols();
  // Every rank receives every rank's subtree roots: the bound is shared.
  const std::size_t group =
      std::max<std::size_t>(1, kGroupBytes / std::size_t(rows.parts->count()) /
                                   (sizeof(double) * std::size_t(n) * std::size_t(n)));
  std::vector<int> scattered;
  for (std::size_t i = 0; i < which.size(); ++i)
    if (!gathered[i]) scattered.push_back(int(i));
  Blocks total;
  std::vector<bool> wanted(static_cast<std::size_t>(means.rows()), false);
  tbb::enumerable_thread_specific<ScatterScratch> scratch;
  for (std::size_t start = 0; start < scattered.size(); start += group) {
    std::fill(wanted.begin(), wanted.end(), false);
    for (std::size_t i = start; i < std::min(scattered.size(), start + group); ++i)
      wanted[std::size_t(which[std::size_t(scattered[i])])] = true;
    total.merge(rows.parts->sum_blocks(
        [&](Eigen::Index s) { return segment_scatter(rows, labels, means, wanted, s, scratch); }));
  }
  std::map<int, Eigen::MatrixXd> scatter;
  for (int i : scattered) {
    Eigen::MatrixXd& m = scatter[i];
    const auto it = total.find(which[std::size_t(i)]);
    m = Eigen::MatrixXd::Zero(n, n);
    if (it == total.end()) continue;
    std::size_t at = 0;
    for (Eigen::Index c = 0; c < n; ++c)
      for (Eigen::Index r = c; r < n; ++r) m(r, c) = m(c, r) = it->second[at++];
  }
  return scatter;
}

// Keeps the leading eigenpairs as the model's principal directions: rows of
// `directions` (not yet normalised), stopping at the numerical rank.
void keep_directions(const Eigen::VectorXd& values, const Eigen::MatrixXd& directions,
                     ClusterModel& model) {
  const Eigen::Index c = model.basis.rows();
  const double largest = std::max(values.size() ? values[0] : 0.0, 0.0);
  const double cutoff = std::max(largest * 1e-12, 1e-300);
  for (Eigen::Index i = 0; i < c && i < values.size(); ++i) {
    const double lambda = values[i];
    if (!(lambda > cutoff)) break;  // rank reached: the rest stay zero
    const double norm = directions.col(i).norm();
    if (!(norm > 0) || !std::isfinite(norm)) break;
    model.basis.row(i) = directions.col(i).transpose() / norm;
    model.eigenvalues[i] = lambda;
  }
}

// A cluster's centred members Y (m x n, rows in global row order, so the
// same bits on any number of ranks), laid out for lower_product: Y itself
// for the n x n scatter Y^T Y, or Y^T for the m x m Gram matrix Y Y^T of a
// cluster of m < n points, which shares the scatter's nonzero eigenvalues
// (Y^T w is the scatter's eigenvector for the Gram's eigenvector w): m^3
// instead of n^3.
struct CentredMembers {
  const double* a = nullptr;
  Eigen::Index depth = 0, width = 0, stride = 0;
};

// 64-byte aligned: a tile's vectors are whole cache lines.
using AlignedDoubles = std::vector<double, Eigen::aligned_allocator<double>>;

// Y from member q's float row `row(q)` less the mean, in double, into
// `storage` (kept from batch to batch: fresh matrices per cluster cost page
// faults), its rows padded with zeros.
template <class Row>
CentredMembers centre_members(Eigen::Index m, const Row& row, const Eigen::RowVectorXd& mean,
                              bool gram, AlignedDoubles& storage) {
  const Eigen::Index n = mean.size();
  CentredMembers y;
  y.depth = gram ? n : m;
  y.width = gram ? m : n;
  y.stride = (y.width + kLowerProductLanes - 1) / kLowerProductLanes * kLowerProductLanes;
  storage.assign(std::size_t(y.depth * y.stride), 0.0);
  if (!gram) {
    for (Eigen::Index q = 0; q < m; ++q) {
      const auto x = row(q);
      for (Eigen::Index i = 0; i < n; ++i)
        storage[std::size_t(q * y.stride + i)] = double(x[i]) - mean[i];
    }
  } else {
    // Eight members at a time: whole cache lines of Y^T per dimension.
    for (Eigen::Index q0 = 0; q0 < m; q0 += kLowerProductLanes) {
      const Eigen::Index count = std::min(kLowerProductLanes, m - q0);
      const float* source[kLowerProductLanes];
      for (Eigen::Index r = 0; r < count; ++r) source[r] = row(q0 + r).data();
      for (Eigen::Index i = 0; i < n; ++i)
        for (Eigen::Index r = 0; r < count; ++r)
          storage[std::size_t(i * y.stride + q0 + r)] = double(source[r][i]) - mean[i];
    }
  }
  y.a = storage.data();
  return y;
}

// The directions Y^T w from the Gram matrix's pairs.
void directions_from_gram(const CentredMembers& y, const Eigenpairs& pairs, ClusterModel& model) {
  if (pairs.values.size() == 0) return;  // not finite: the model keeps zero rows
  // Y^T w_i loses orthogonality as eps lambda_max / lambda_i: one modified
  // Gram-Schmidt pass, largest first (a rounding-level change for the others).
  const Eigen::Map<const RowMatrixXd, 0, Eigen::OuterStride<>> transposed(
      y.a, y.depth, y.width, Eigen::OuterStride<>(y.stride));
  Eigen::MatrixXd directions = transposed * pairs.vectors;
  for (Eigen::Index i = 0; i < directions.cols(); ++i) {
    for (Eigen::Index j = 0; j < i; ++j)
      directions.col(i) -= directions.col(j).dot(directions.col(i)) * directions.col(j);
    const double norm = directions.col(i).norm();
    if (norm > 0 && std::isfinite(norm)) directions.col(i) /= norm;
  }
  keep_directions(pairs.values, directions, model);
}

// Batches of up to eight of `solved` (indices into which) with one component
// count and one kind (Gram or scatter), sizes close together:
// largest_eigenpairs_batch pads a batch to its largest. Matrices too large
// to batch are solved one per task, on every core.
std::vector<std::vector<std::size_t>> solve_batches(std::vector<std::size_t> solved,
                                                    const std::vector<int>& which,
                                                    const std::vector<bool>& gram,
                                                    const std::vector<double>& counts,
                                                    const std::vector<ClusterModel>& models,
                                                    Eigen::Index dimension) {
  constexpr std::size_t kBatch = 8;
  const auto size = [&](std::size_t i) {
    return gram[i] ? counts[std::size_t(which[i])] : double(dimension);
  };
  const auto key = [&](std::size_t i) {
    return std::tuple(models[std::size_t(which[i])].basis.rows(), bool(gram[i]), size(i));
  };
  std::stable_sort(solved.begin(), solved.end(),
                   [&](std::size_t a, std::size_t b) { return key(a) < key(b); });
  std::vector<std::vector<std::size_t>> batches;
  for (std::size_t i : solved) {
    if (batches.empty() || batches.back().size() == kBatch ||
        size(i) > double(kLargestBatchedEigen) ||
        size(batches.back().front()) > double(kLargestBatchedEigen) ||
        std::get<0>(key(batches.back().front())) != std::get<0>(key(i)) ||
        std::get<1>(key(batches.back().front())) != std::get<1>(key(i)))
      batches.emplace_back();
    batches.back().push_back(i);
  }
  return batches;
}

}  // namespace

namespace {

// Each cluster's mean, and a zero model sized for its components; a model
// whose members did not change is reused. Returns the clusters left to solve.
std::vector<int> start_models(const ClusterSums& sums, const std::vector<int>& components,
                              const FitReuse* reuse, Eigen::Index n,
                              std::vector<ClusterModel>& models, RowMatrixXd& means) {
  std::vector<int> which;
  for (int j = 0; j < int(models.size()); ++j) {
    const int c = std::max(0, components[std::size_t(j)]);
    if (reuse && !reuse->changed[std::size_t(j)] &&
        (*reuse->previous)[std::size_t(j)].basis.rows() >= std::min(c, reuse->minimum)) {
      models[std::size_t(j)] = (*reuse->previous)[std::size_t(j)];  // same members, same model
      continue;
    }
    models[std::size_t(j)] = {Eigen::RowVectorXd::Zero(n), RowMatrixXd::Zero(c, n),
                              Eigen::VectorXd::Zero(c)};
    if (sums.counts[std::size_t(j)] == 0) continue;
    means.row(j) = sums.sums.row(j) / sums.counts[std::size_t(j)];
    models[std::size_t(j)].mean = means.row(j);
    if (c > 0) which.push_back(j);
  }
  return which;
}

// Per thread, kept from batch to batch: the batch's centred members and
// their matrices (a scatter of the last batch's size is reused without a
// new allocation; a Gram matrix of another size is reallocated).
struct BatchScratch {
  std::vector<AlignedDoubles> centred;
  std::vector<Eigen::MatrixXd> matrices;
};

// What solving the clusters' models needs, made once per refit.
struct ClusterSolve {
  const Rows& rows;
  const std::vector<int>& which;      // the clusters to solve
  const std::vector<bool>& gram;      // from the Gram matrix (else the scatter)
  const std::vector<bool>& gathered;  // members gathered (else the scatter summed over segments)
  const std::vector<std::vector<std::uint32_t>>& members;
  const std::map<int, MatrixXfRow>& gathered_members;  // ranks: the members gathered here
  const std::map<int, Eigen::MatrixXd>& summed;        // scatters summed over segments
  std::vector<ClusterModel>& models;

  // One batch of clusters: their matrices, one batched eigen-solve, their models.
  void solve(const std::vector<std::size_t>& batch, BatchScratch& scratch) const {
    const Eigen::Index count = models[std::size_t(which[batch.front()])].basis.rows();
    scratch.centred.resize(std::max(scratch.centred.size(), batch.size()));
    scratch.matrices.resize(std::max(scratch.matrices.size(), batch.size()));
    std::vector<CentredMembers> centred(batch.size());
    std::vector<const Eigen::MatrixXd*> matrices;
    for (std::size_t q = 0; q < batch.size(); ++q) {
      const std::size_t i = batch[q];
      if (!gathered[i]) {
        matrices.push_back(&summed.at(int(i)));
        continue;
      }
      centred[q] = centre(i, scratch.centred[q]);
      lower_product(centred[q].a, centred[q].depth, centred[q].width, centred[q].stride,
                    scratch.matrices[q]);
      matrices.push_back(&scratch.matrices[q]);
    }
    const std::vector<Eigenpairs> pairs = largest_eigenpairs_batch(matrices, count);
    for (std::size_t q = 0; q < batch.size(); ++q) {
      ClusterModel& model = models[std::size_t(which[batch[q]])];
      if (gram[batch[q]])
        directions_from_gram(centred[q], pairs[q], model);
      else
        keep_directions(pairs[q].values, pairs[q].vectors, model);
    }
  }

  // Cluster i's members less its mean, from where they lie (or were gathered).
  CentredMembers centre(std::size_t i, AlignedDoubles& storage) const {
    const ClusterModel& model = models[std::size_t(which[i])];
    if (rows.distributed()) {
      const MatrixXfRow& y = gathered_members.at(int(i));
      return centre_members(
          y.rows(), [&](Eigen::Index p) { return y.row(p); }, model.mean, gram[i], storage);
    }
    const std::vector<std::uint32_t>& list = members[std::size_t(which[i])];
    CentredMembers out = centre_members(
        Eigen::Index(list.size()), [&](Eigen::Index p) { return rows.x.row(list[std::size_t(p)]); },
        model.mean, gram[i], storage);
    // Its members' pages go at once (most clusters are small for wide rows).
    for (std::uint32_t p : list) rows.release(p, p + 1);
    return out;
  }
};

// Each rank solved every size-th cluster: the ranks share their models.
void share_models(const Rows& rows, const std::vector<int>& which,
                  std::vector<ClusterModel>& models) {
  const int rank = rows.parts->index(), ranks = rows.parts->count();
  std::vector<double> mine;
  for (std::size_t i = std::size_t(rank); i < which.size(); i += std::size_t(ranks)) {
    const ClusterModel& m = models[std::size_t(which[i])];
    mine.insert(mine.end(), m.basis.data(), m.basis.data() + m.basis.size());
    mine.insert(mine.end(), m.eigenvalues.data(), m.eigenvalues.data() + m.eigenvalues.size());
  }
  const auto all = rows.parts->allgather(mine);
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

}  // namespace

std::vector<ClusterModel> fit_models(const Rows& rows, const std::vector<std::int32_t>& labels,
                                     int k, const std::vector<int>& components,
                                     std::vector<double>* counts, const FitReuse* reuse) {
  const Eigen::Index n = rows.cols();
  const ClusterSums sums = cluster_sums(rows, labels, k);
  std::vector<ClusterModel> models(static_cast<std::size_t>(k));
  RowMatrixXd means = RowMatrixXd::Zero(k, n);
  const std::vector<int> which = start_models(sums, components, reuse, n, models, means);
  // Small clusters from their Gram matrix, the others from their scatter;
  // both from the members gathered where the cluster is solved, in global
  // row order, except clusters too large to gather, whose scatter is summed
  // over segments. The choices depend on the global count only, so every
  // rank makes them alike.
  std::vector<bool> gram(which.size()), gathered(which.size());
  for (std::size_t i = 0; i < which.size(); ++i) {
    const double count = sums.counts[std::size_t(which[i])];
    gram[i] = count < double(n);
    gathered[i] = count <= double(kGatheredPointsPerDimension) * double(n);
  }
  const auto members = members_of(labels, k);
  // A single process reads members where they are; ranks gather them.
  const std::map<int, MatrixXfRow> gathered_members =
      rows.distributed() ? gathered_rows(rows, members, which, gathered, sums.counts)
                         : std::map<int, MatrixXfRow>();
  const std::map<int, Eigen::MatrixXd> summed =
      cluster_scatter(rows, labels, means, which, gathered);
  // Each rank solves every size-th cluster and the ranks share the results
  // (the same solver on the same matrix gives the same bits anywhere).
  const int rank = rows.parts->index(), ranks = rows.parts->count();
  // Eight clusters per solve (largest_eigenpairs_batch: a cluster's result
  // does not depend on which clusters share its batch), the batches on every
  // core.
  std::vector<std::size_t> mine;
  for (std::size_t i = std::size_t(rank); i < which.size(); i += std::size_t(ranks))
    mine.push_back(i);
  const std::vector<std::vector<std::size_t>> batches =
      solve_batches(std::move(mine), which, gram, sums.counts, models, n);
  const ClusterSolve solve{rows, which, gram, gathered, members, gathered_members, summed, models};
  tbb::enumerable_thread_specific<BatchScratch> batch_scratch;
  tbb::parallel_for(std::size_t(0), batches.size(), [&](std::size_t b) {
    Progress::check_interrupt();  // eight eigen-solves may take a while (glossy rows)
    solve.solve(batches[b], batch_scratch.local());
  });
  rows.release_all();  // the gathered clusters' members, read where they lie
  if (ranks > 1) share_models(rows, which, models);
  if (counts) *counts = sums.counts;
  return models;
}

}  // namespace prt::clustering
