// A^T A for the CPCA refit: a cluster's scatter (A = its centred members,
// one per row) or Gram matrix (A = their transpose, one dimension per row).
//
// Eigen's symmetric rank update ran at 10.5-15 G multiply-adds/s on one core
// at these sizes (147-256 members, 100-600 dimensions; a micro-benchmark): its
// blocking and packing are made for larger products. Here a tile of 24
// result rows by 8 columns keeps its sums in registers over the whole depth.
#pragma once
#include <Eigen/Core>

namespace prt::clustering {

// Result rows per vector of doubles; A's row stride must be a multiple.
inline constexpr Eigen::Index kLowerProductLanes = 8;

// The `width` x `width` product A^T A, both triangles, for A of `depth` rows
// of `width` values, rows `stride` apart (a multiple of kLowerProductLanes),
// the values from `width` to `stride` zero. Each entry is one chain of
// multiply-adds in row order, computed once for the lower triangle and
// mirrored: the same bits on any thread or rank.
void lower_product(const double* a, Eigen::Index depth, Eigen::Index width, Eigen::Index stride,
                   Eigen::MatrixXd& out);

}  // namespace prt::clustering
