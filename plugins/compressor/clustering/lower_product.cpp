#include "lower_product.hpp"

#include <algorithm>
#include <cstring>

namespace prt::clustering {

namespace {

typedef double Lanes __attribute__((vector_size(64)));
static_assert(sizeof(Lanes) == kLowerProductLanes * sizeof(double));

constexpr int kVectors = 3;  // result rows per tile: 3 x 8
constexpr int kColumns = 8;  // result columns per tile

// Rows [p, p + 8 V) by columns [q, q + 8) of A^T A: 8 V sums per column in
// registers, each column's A value broadcast to the V vectors.
template <int V>
void tile(const double* a, Eigen::Index depth, Eigen::Index stride, Eigen::Index p, Eigen::Index q,
          Lanes (&sums)[kVectors][kColumns]) {
  Lanes sum[V][kColumns] = {};
  for (Eigen::Index i = 0; i < depth; ++i) {
    const double* row = a + i * stride;
    Lanes rows[V];
    for (int v = 0; v < V; ++v) {
      std::memcpy(&rows[v], row + p + v * kLowerProductLanes, sizeof(Lanes));
#ifdef __AVX512F__
      asm("" : "+v"(rows[v]));  // in a register for all 8 columns
#endif
    }
    for (int c = 0; c < kColumns; ++c) {
      const double column = row[q + c];
      for (int v = 0; v < V; ++v) sum[v][c] += rows[v] * column;
    }
  }
  for (int v = 0; v < V; ++v)
    for (int c = 0; c < kColumns; ++c) sums[v][c] = sum[v][c];
}

}  // namespace

void lower_product(const double* a, Eigen::Index depth, Eigen::Index width, Eigen::Index stride,
                   Eigen::MatrixXd& out) {
  out.resize(width, width);
  for (Eigen::Index q = 0; q < width; q += kColumns) {
    for (Eigen::Index p = q / kLowerProductLanes * kLowerProductLanes; p < width;
         p += kVectors * kLowerProductLanes) {
      const int vectors = int(std::min<Eigen::Index>(
          kVectors, (width - p + kLowerProductLanes - 1) / kLowerProductLanes));
      Lanes sums[kVectors][kColumns];
      if (vectors == 3)
        tile<3>(a, depth, stride, p, q, sums);
      else if (vectors == 2)
        tile<2>(a, depth, stride, p, q, sums);
      else
        tile<1>(a, depth, stride, p, q, sums);
      for (int v = 0; v < vectors; ++v)
        for (int c = 0; c < kColumns && q + c < width; ++c)
          for (Eigen::Index r = 0; r < kLowerProductLanes; ++r) {
            const Eigen::Index row = p + v * kLowerProductLanes + r;
            if (row < width && row >= q + c) out(row, q + c) = sums[v][c][r];
          }
    }
  }
  out.triangularView<Eigen::StrictlyUpper>() = out.transpose();
}

}  // namespace prt::clustering
