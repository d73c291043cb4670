// Products of the cosine-weighted visibility matrix T with dense matrices,
// visiting only the (vertex, direction) pairs that see each other.
//
// T has a row per vertex and a column per direction of a set: T_vk =
// (n_v . d_k) / pi where visibility bit (v, k) is set (bits are set only above
// the tangent plane), 0 elsewhere. Half or more of T is zero (below the
// horizon or occluded), so these kernels cost less than a dense product of
// the same shape and never build T's rows.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "prt/direction_set.hpp"
#include "prt/mesh.hpp"
#include "prt/row_parts.hpp"

namespace prt {

class VisibilityBits;

// A dense matrix stored row-major, each row padded with zeros to whole
// packets of 8 doubles, so that a kernel adds a row with full-width vector
// operations.
class PaddedRows {
 public:
  PaddedRows() = default;
  PaddedRows(Eigen::Index rows, Eigen::Index cols);  // zeros
  explicit PaddedRows(const Eigen::MatrixXd& matrix);
  // Takes the shape and values of `matrix`, keeping the storage when it is
  // large enough: buffers reused across passes cost no page faults (a fresh
  // page costs ~3 ms per MB on this project's VMs).
  template <class Derived>
  void assign(const Eigen::MatrixBase<Derived>& matrix) {
    resize(matrix.rows(), matrix.cols());
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>, 0,
               Eigen::OuterStride<>>(data_.data(), rows_, cols_, Eigen::OuterStride<>(stride_)) =
        matrix;
  }
  void resize(Eigen::Index rows, Eigen::Index cols);  // zeros, keeping the storage

  Eigen::Index rows() const { return rows_; }
  Eigen::Index cols() const { return cols_; }
  Eigen::Index stride() const { return stride_; }  // doubles per stored row
  double* row(Eigen::Index r) { return data_.data() + r * stride_; }
  const double* row(Eigen::Index r) const { return data_.data() + r * stride_; }
  // The rows [first, first + count) without the padding (a view).
  using ConstBlock =
      Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>, 0,
                 Eigen::OuterStride<>>;
  ConstBlock block(Eigen::Index first, Eigen::Index count) const;
  ConstBlock matrix_view() const { return block(0, rows_); }
  Eigen::MatrixXd matrix() const { return block(0, rows_); }

 private:
  Eigen::Index rows_ = 0, cols_ = 0, stride_ = 0;
  std::vector<double> data_;
};

// Visibility bits transposed: a row of bits per direction over the
// vertices, so that T^T is a product of the same form as T (29 MB for the
// bunny at 6,144 directions, as the bits themselves).
class TransposedVisibility {
 public:
  explicit TransposedVisibility(const VisibilityBits& visibility);
  std::size_t vertices() const { return vertices_; }
  std::size_t directions() const { return directions_; }
  std::size_t words_per_direction() const { return words_per_direction_; }
  const std::uint64_t* words(std::size_t direction) const {
    return bits_.data() + direction * words_per_direction_;
  }

 private:
  std::size_t vertices_, directions_, words_per_direction_;
  std::vector<std::uint64_t> bits_;
};

// out (count x right.cols()) = the rows of T of `count` vertices times
// `right` (directions x columns). `vertices` names each row's vertex;
// `bits` holds their visibility words one vertex after another. Each row
// adds its directions in increasing order, whatever the block.
void visible_times(const Mesh& mesh, const DirectionSet& set, const std::uint32_t* vertices,
                   std::size_t count, const std::uint64_t* bits, const PaddedRows& right,
                   PaddedRows& out);

// Vertices per block of the bake's projection (visible_times_in_blocks):
// the slabs of a per-vertex transfer and the ranks' shards are whole
// blocks, so that their rows are the whole mesh's, bit for bit.
constexpr std::size_t kProjectionBlock = 256;

// The bake's projection: T right for the mesh's vertices [first, last), as
// floats into `out` (vertex first + i's row at out + i * out_stride), from
// their visibility words (vertex first + i's at bits + i * words), on every
// core. The vertices go in blocks of the mesh's grid of kProjectionBlock
// (cut at first and last), each block along its Morton curve; a vertex's
// sums N = sum over its set bits j of d_j (x) right.row(j) are carried from
// the one of the 32 vertices before it whose bits differ least, adding and
// removing only the directions where they differ (3 multiply-adds per
// differing pair instead of one per set bit: ~0.3-0.45 of the work for the
// bunny), and its row is n . N / pi. Each row depends on its block's
// vertices and bits alone: the same bits on any number of cores, and for
// any range whose ends are multiples of kProjectionBlock (or the mesh's
// end).
void visible_times_in_blocks(const Mesh& mesh, const DirectionSet& set, std::size_t first,
                             std::size_t last, const std::uint64_t* bits, const PaddedRows& right,
                             float* out, std::size_t out_stride);

// T right for all of `visibility`'s vertices, on every core; `out` keeps its
// storage when it has the shape already. The bits' rows are the mesh's
// vertices from `first_vertex` on (a rank's shard; default all). Rows are
// summed along chains of 64 vertices on the Morton curve of each segment of
// the mesh (kSegmentRows): a row's sums are carried from its neighbour's,
// adding only the directions where their bits differ. The chains depend on
// the mesh and the segments alone, so a shard that starts at a segment and
// ends at one (or at the mesh's end) gets the whole product's rows, bit for
// bit, on any number of cores.
void visible_times(const Mesh& mesh, const DirectionSet& set, const VisibilityBits& visibility,
                   const PaddedRows& right, PaddedRows& out, std::size_t first_vertex = 0);
Eigen::MatrixXd visible_times(const Mesh& mesh, const DirectionSet& set,
                              const VisibilityBits& visibility, const Eigen::MatrixXd& right);

// T^T left (left: a row per vertex), on every core. Each output row adds its
// vertices in increasing order: the same bits whatever the number of cores.
void visible_transpose_times(const Mesh& mesh, const DirectionSet& set,
                             const TransposedVisibility& transposed, const PaddedRows& left,
                             PaddedRows& out);
Eigen::MatrixXd visible_transpose_times(const Mesh& mesh, const DirectionSet& set,
                                        const TransposedVisibility& transposed,
                                        const Eigen::MatrixXd& left);
// The same, transposing the bits first (for a single product).
Eigen::MatrixXd visible_transpose_times(const Mesh& mesh, const DirectionSet& set,
                                        const VisibilityBits& visibility,
                                        const Eigen::MatrixXd& left);

// T^T left over the vertices of this part's shard (the bits' and left's rows
// are the mesh's vertices parts.shard()), summed over every part's shard
// (RowParts::sum): one partial per segment of vertices, added along a fixed
// tree. Within a segment, directions are summed along chains of 64
// consecutive directions, each carried from the one before it (as
// visible_times' vertices). The result is on every part, the same bits for
// any number of parts and cores (not those of visible_transpose_times, which
// adds every vertex in one running sum, directly).
Eigen::MatrixXd visible_transpose_sum(const Mesh& mesh, const DirectionSet& set,
                                      const TransposedVisibility& transposed,
                                      const PaddedRows& left, const RowParts& parts);

}  // namespace prt
