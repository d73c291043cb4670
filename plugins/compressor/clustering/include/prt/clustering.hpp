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
#include <string>
#include <vector>

#include "prt/mesh.hpp"
#include "prt/transfer.hpp"

namespace prt::clustering {

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

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
Clusters lbg(const MatrixXfRow& x, const LbgOptions& options);

// Mean and orthonormal principal directions of one cluster.
struct ClusterModel {
  Eigen::RowVectorXd mean;
  RowMatrixXd basis;            // components x n, orthonormal rows (zero rows past the rank)
  Eigen::VectorXd eigenvalues;  // D_i^2 of each basis row, descending
};

// PCA of the rows `members` of x, through the eigen-solve of C^T C or C C^T,
// whichever is smaller. Clusters with fewer points than components, single
// points and identical points give zero rows, never NaN.
ClusterModel fit_cluster(const MatrixXfRow& x, const std::vector<std::uint32_t>& members,
                         int components);

// Members of each cluster, in increasing vertex order.
std::vector<std::vector<std::uint32_t>> members_of(const std::vector<std::int32_t>& labels,
                                                   int clusters);

// Builds the compressed form: per-vertex weights (x - mean) . basis^T.
CompressedTransfer assemble(const MatrixXfRow& x, const std::vector<std::int32_t>& labels,
                            const std::vector<ClusterModel>& models, const std::string& name);

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

CpcaResult cpca(const MatrixXfRow& x, const CpcaOptions& options);

// Squared approximation error of row p under a cluster model.
double approximation_error(const MatrixXfRow& x, Eigen::Index p, const ClusterModel& model);

// --- cluster coherence (Sloan 2003 §5, Chen 2005 ch. 4) ---

// Moves boundary vertices into a neighbour's cluster in decreasing order of
// overdraw reduction per unit error increase, until the total squared error
// has grown by `error_budget` (e.g. 0.05 = 5%). Re-projects moved vertices.
// Returns the number of vertices moved.
std::size_t reclassify(const MatrixXfRow& x, const Mesh& mesh, double error_budget,
                       CompressedTransfer& compressed);

enum class SuperclusterMethod { greedy_merge, chen_selection };

// Groups clusters into superclusters of at most `max_clusters` clusters each:
// greedy_merge repeatedly merges the adjacent pair that shares the most
// triangles (Sloan); chen_selection grows one supercluster at a time from the
// most populous unselected cluster (Chen, Fig. 4.6). Sets
// compressed.supercluster_of_cluster.
void supercluster(const Mesh& mesh, int max_clusters, SuperclusterMethod method,
                  CompressedTransfer& compressed);

}  // namespace prt::clustering
