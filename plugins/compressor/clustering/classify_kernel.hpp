// The classification of iterative and adaptive CPCA as one pass over the
// data: every row's dots with every cluster's mean and components, the
// approximation error of each cluster, and the first cluster of least error.
//
// A general float GEMM made the products (37,706 x 2,304 floats per
// 100-dim iteration), wrote them out and read them back for the sums. Here
// the classifier is packed once per iteration, sixteen clusters to a vector
// (one panel per group of clusters: dimension-major, then the mean and
// each component), so that each dot stays in a register from its first
// multiply-add to its squared distance, and a block of rows is read while
// its panels stay in L2.
//
// Each dot is one chain of multiply-adds in dimension order, so a row's
// label does not depend on its block, its thread or the number of ranks.
#pragma once
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "prt/clustering.hpp"

namespace prt::clustering {

// Sixteen clusters per vector: one AVX-512 register of floats.
inline constexpr int kClassifyLanes = 16;

struct PackedClassifier {
  Eigen::Index dimension = 0;  // n
  int clusters = 0;            // k
  int groups = 0;              // ceil(k / 16)
  // Per group: the mean, then each component up to the group's widest
  // cluster (1 + its component count).
  std::vector<int> types;
  // Per group, where its offsets start (in floats; its panel starts at n
  // times that): the sum of the earlier groups' types x 16.
  std::vector<std::size_t> panel_start;
  // Group g's panel at panels[panel_start[g] n ...]: [i][type][lane], the
  // dimension i of the mean (type 0) or of component type - 1 of cluster
  // 16 g + lane; zero where the cluster has no such component, so it adds an
  // exact zero to its sum.
  std::vector<float, Eigen::aligned_allocator<float>> panels;
  // offsets[panel_start[g] + type 16 + lane]: u . m for components, 0 for the mean.
  std::vector<float, Eigen::aligned_allocator<float>> offsets;
  // |m|^2 per cluster, padded to whole groups.
  std::vector<float, Eigen::aligned_allocator<float>> mean_norms;
};

// The first `components` directions of each model and its mean, in float.
PackedClassifier pack_classifier(const std::vector<ClusterModel>& models, int components);

// Rows per block for classify_rows: ~256 KB of rows, so that a block stays
// in L2 beside a group's panel, in whole tiles of rows.
Eigen::Index classify_block_rows(Eigen::Index dimension);

// Labels rows [begin, end) of x: the first cluster of least
// |x - m_j|^2 - sum_t ((x - m_j) . u_jt)^2, in float as
// ((|x|^2 - 2 x . m_j) + |m_j|^2) - sum_t (x . u_jt - u_jt . m_j)^2.
// `errors` is scratch, resized as needed. Throws when x's rows are not of
// the models' dimension.
void classify_rows(RowsRef x, Eigen::Index begin, Eigen::Index end, const PackedClassifier& c,
                   std::int32_t* labels, std::vector<float>& errors);

// The same over kept errors: `c` packs some of `all` clusters (packed
// cluster j is cluster clusters[j]); their errors for rows [begin, end)
// replace those in `kept` (a row of `all` floats per row, from row begin),
// and each row's label is the first least of its kept row. A cluster's
// error depends on its own model and the row alone (lanes never mix), so a
// model that did not change keeps its errors' bits.
void classify_rows_kept(RowsRef x, Eigen::Index begin, Eigen::Index end, const PackedClassifier& c,
                        const std::vector<int>& clusters, float* kept, int all,
                        std::int32_t* labels, std::vector<float>& errors);

}  // namespace prt::clustering
