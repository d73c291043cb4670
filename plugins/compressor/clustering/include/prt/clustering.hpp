// Clustering and per-cluster PCA for the compressor plug-ins (Sloan et al.
// 2003 §4-5, Chen 2005 ch. 3-4): LBG/k-means, static, iterative and adaptive
// clustered PCA, and the cluster-coherence passes (reclassification and
// superclustering) that lower overdraw.
//
// Data are v x n float rows (the stored transfer); means, bases and errors are
// computed in double; distances for classification come from float GEMMs
// (blocked, TBB over row blocks) and are exact enough to choose a cluster.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "prt/mesh.hpp"
#include "prt/row_parts.hpp"
#include "prt/transfer.hpp"

namespace prt {
class PartKeeper;
}

namespace prt::clustering {

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
// Float rows in memory or in a mapped file (TransferSignal::rows()).
using RowsRef = Eigen::Ref<const MatrixXfRow>;

// The rows of the signal this process holds and where they sit in the whole:
// all of them in a single process, a shard of whole segments in a distributed
// run. Every sum over rows goes through the parts' fixed tree
// (prt/row_parts.hpp), so a result depends on
// neither the thread count nor the rank count. Labels, errors and weights
// are per local row; means and models are the same on every rank. A signal
// whose rows are in a file (out of core) is read in passes: each pass
// releases the rows it is done with.
struct Rows {
  explicit Rows(RowsRef x);  // contiguous rows in memory
  explicit Rows(const TransferSignal& signal);
  Rows(const MatrixXfRow& local, std::shared_ptr<const RowParts> parts);
  Rows(const TransferSignal& local, std::shared_ptr<const RowParts> parts);
  Eigen::Map<const MatrixXfRow> x;
  std::shared_ptr<const RowParts> parts;   // never null
  Shard shard;                             // parts->shard()
  const TransferSignal* signal = nullptr;  // set when made from one: releases go to it

  // Lets local rows [begin, end) go when they are in a file (no-op in memory).
  void release(Eigen::Index begin, Eigen::Index end) const {
    if (signal) signal->release(begin, end);
  }
  void release_all() const { release(0, local()); }

  bool distributed() const { return parts->distributed(); }
  Eigen::Index local() const { return x.rows(); }
  Eigen::Index total() const { return shard.total; }
  Eigen::Index cols() const { return x.cols(); }
  // Local rows [begin, end) of segment s of the whole signal.
  std::pair<Eigen::Index, Eigen::Index> segment_rows(Eigen::Index segment) const;
  // Sum of one value per local row over the whole signal.
  double sum(const std::vector<double>& per_row) const;
  // Row `global` of the whole signal, on every rank.
  Eigen::RowVectorXd fetch(Eigen::Index global) const;
  // True on every rank when it is true on any.
  bool any(bool mine) const;
};

// Per cluster: the sum of its rows and their count (label -1: in none).
struct ClusterSums {
  RowMatrixXd sums;            // k x n
  std::vector<double> counts;  // k
};
ClusterSums cluster_sums(const Rows& rows, const std::vector<std::int32_t>& labels, int clusters);
// The counts alone (the same figures as cluster_sums' counts; no row is read).
std::vector<double> cluster_counts(const Rows& rows, const std::vector<std::int32_t>& labels,
                                   int clusters);

// One iteration of an iterative algorithm, for benchmarks: its wall time and
// the shape (rows x inner x cols) of its dominant matrix product.
struct IterationLog {
  double seconds = 0;
  double energy = 0;
  Eigen::Index rows = 0, inner = 0, cols = 0;
  std::string stage;
};

enum class Init { hyperbox, kmeans_plus_plus };

struct LbgOptions {
  int clusters = 256;
  Init init = Init::hyperbox;
  int max_iterations = 30;
  double tolerance = 1e-4;  // stop when (E_prev - E) / E_prev < tolerance
  std::uint64_t seed = 1;
  // Chen's geometry-coherent classification: E = |x - mean| + alpha * (distance
  // from the vertex to the nearest other point of the cluster). Needs a mesh.
  double alpha = 0;
  const Mesh* mesh = nullptr;
  // Where the iterations keep their state (means, labels, energy), at most
  // every keep_seconds; a rerun finds it and continues from there, with
  // the result an uninterrupted run gives. One process only.
  const PartKeeper* keep = nullptr;
  double keep_seconds = 60;
};

struct Clusters {
  std::vector<std::int32_t> labels;  // v
  RowMatrixXd means;                 // k x n
  double energy = 0;                 // sum of squared distances to the means
  int iterations = 0;
  std::vector<IterationLog> log;
};

// LBG / k-means. Empty clusters are refilled by splitting the most populous
// one (its point farthest from its mean seeds the empty cluster), so every
// cluster ends non-empty when there are at least k distinct points.
Clusters lbg(const Rows& rows, const LbgOptions& options);
inline Clusters lbg(RowsRef x, const LbgOptions& options) {
  return lbg(Rows(x), options);
}

// Mean and orthonormal principal directions of one cluster.
struct ClusterModel {
  Eigen::RowVectorXd mean;
  RowMatrixXd basis;            // components x n, orthonormal rows (zero rows past the rank)
  Eigen::VectorXd eigenvalues;  // D_i^2 of each basis row, descending
};

// A previous fit that fit_models may keep: clusters whose members have not
// changed since it get its model back when it has at least
// min(components, minimum) directions (what a refit asking the same number of
// directions would give; asked for more, MRRR's vectors may differ in their
// last bits). Deterministic on any number of cores or ranks either way.
struct FitReuse {
  const std::vector<ClusterModel>* previous = nullptr;
  std::vector<char> changed;  // per cluster, as changed_clusters gives it
  int minimum = 0;
};

// A cluster of at most this many points per dimension (8n points of n
// values) has its members gathered, where it is solved, to make its scatter
// or Gram matrix: at most 8n^2 values per cluster, as in the Gram path (n^2).
// A larger cluster's scatter is summed over segments instead, whose partials
// are n x n whatever its size, so that an out-of-core or distributed fit never
// holds a large cluster's rows.
inline constexpr int kGatheredPointsPerDimension = 8;

// Mean and PCA of every cluster: the largest eigenpairs of each cluster's
// n x n scatter about its mean, or for clusters with fewer than n points of
// their Gram matrix, both from its members in vertex order (one product, the
// same bits on any number of ranks); the scatter of a cluster of more than
// kGatheredPointsPerDimension * n points is summed over segments. Clusters
// with fewer points than components, single points and identical points give
// zero rows, never NaN. `counts` gets each cluster's size.
std::vector<ClusterModel> fit_models(const Rows& rows, const std::vector<std::int32_t>& labels,
                                     int clusters, const std::vector<int>& components,
                                     std::vector<double>* counts = nullptr,
                                     const FitReuse* reuse = nullptr);

// Per cluster: whether any row entered or left it between two labellings
// (on every rank).
std::vector<char> changed_clusters(const Rows& rows, const std::vector<std::int32_t>& before,
                                   const std::vector<std::int32_t>& after, int clusters);

// PCA of the rows `members` of x (one cluster of fit_models).
ClusterModel fit_cluster(RowsRef x, const std::vector<std::uint32_t>& members, int components);

// Members of each cluster, in increasing vertex order.
std::vector<std::vector<std::uint32_t>> members_of(const std::vector<std::int32_t>& labels,
                                                   int clusters);

// Builds the compressed form: per-vertex weights (x - mean) . basis^T (of
// the local rows: a distributed run gathers them with gather_rows).
CompressedTransfer assemble(const Rows& rows, const std::vector<std::int32_t>& labels,
                            const std::vector<ClusterModel>& models, const std::string& name);
inline CompressedTransfer assemble(RowsRef x, const std::vector<std::int32_t>& labels,
                                   const std::vector<ClusterModel>& models,
                                   const std::string& name) {
  return assemble(Rows(x), labels, models, name);
}
// The ranks' compressed rows (weights, cluster ids, sparse indices) joined in
// rank order on rank 0; other ranks keep theirs. Models are already shared.
void gather_rows(const Rows& rows, CompressedTransfer& compressed);

enum class Method { static_pca, iterative, adaptive };

struct CpcaOptions {
  LbgOptions lbg;
  Method method = Method::static_pca;
  int components = 8;  // n' (for adaptive: the average per point)
  int iterations_per_component = 10;
  int adaptive_iterations = 5;
};

struct CpcaResult {
  std::vector<std::int32_t> labels;
  std::vector<ClusterModel> models;
  std::vector<IterationLog> log;
};

CpcaResult cpca(const Rows& rows, const CpcaOptions& options);
inline CpcaResult cpca(RowsRef x, const CpcaOptions& options) {
  return cpca(Rows(x), options);
}

// Squared approximation error of row p under a cluster model (its first
// `components` directions; all of them when negative).
double approximation_error(RowsRef x, Eigen::Index p, const ClusterModel& model,
                           Eigen::Index components = -1);
// The same with buffers reused from row to row (no allocation per row).
struct ErrorScratch {
  Eigen::RowVectorXd centred;
  Eigen::VectorXd projections;
};
double approximation_error(RowsRef x, Eigen::Index p, const ClusterModel& model,
                           Eigen::Index components, ErrorScratch& scratch);

// --- cluster coherence (Sloan 2003 §5, Chen 2005 ch. 4) ---

// Moves boundary vertices into a neighbour's cluster in decreasing order of
// overdraw reduction per unit error increase, until the total squared error
// has grown by `error_budget` (e.g. 0.05 = 5%). Re-projects moved vertices.
// Returns the number of vertices moved.
// `release` (optional) is told the rows each of its two sweeps is done with
// (Rows::release for a signal in a file).
std::size_t reclassify(RowsRef x, const Mesh& mesh, double error_budget,
                       CompressedTransfer& compressed,
                       const std::function<void(Eigen::Index, Eigen::Index)>& release = {});
// The same over the parts of a run, after gather_rows: the first part
// reclassifies every row as one process would (the result is the serial
// run's, bit for bit) and the others take back their rows that changed.
// Returns the number of moves on the first part, 0 elsewhere.
std::size_t reclassify(const Rows& rows, const Mesh& mesh, double error_budget,
                       CompressedTransfer& compressed);
// The whole signal's rows on the first part, in row order; empty elsewhere.
MatrixXfRow gather_signal(const Rows& rows);

enum class SuperclusterMethod { greedy_merge, chen_selection };

// Groups clusters into superclusters of at most `max_clusters` clusters each:
// greedy_merge repeatedly merges the adjacent pair that shares the most
// triangles (Sloan); chen_selection grows one supercluster at a time from the
// most populous unselected cluster (Chen, Fig. 4.6). Sets
// compressed.supercluster_of_cluster.
void supercluster(const Mesh& mesh, int max_clusters, SuperclusterMethod method,
                  CompressedTransfer& compressed);

}  // namespace prt::clustering
