// Relighting at memory speed (Sloan 2003 §6 on the CPU): the one compressed
// form laid out once so that each frame streams its per-vertex data once.
//
// The mesh's vertices are split into one contiguous range per core; within a
// range, vertices are visited in cluster order, so a cluster's constants
// C_ki = M_ki l stay in registers while its vertices' weights stream past;
// weights are stored compactly in that order (n'_k per vertex); the
// constants of every cluster are computed first, into one buffer kept by
// the kernel, from a copy of the cluster data laid out for 16 rows' dots at
// once (ClusterConstants; when there are very many clusters, per part into a
// buffer per task instead); the sums use kernels of fixed n' for the common
// sizes, one call per cluster's run, and are written straight to mesh order.
// Glossy transfer is fused: each vertex's exit-basis values toward the
// camera are dotted with its exit vector without writing the v x 3 N_r exit
// coefficients.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "prt/transfer.hpp"

namespace prt {

// Every cluster's constants C_ki = M_ki l for a light l (N_i x 3): its mean
// and its n'_k representatives, each read as a `rows` x N_i matrix, times l,
// 3 floats per stored row. The cluster data is copied once into panels of 16
// stored rows laid out for 16 rows' dots at once (relight.cpp); each
// compute() splits the panels over the cores and allocates nothing once its
// buffer has its size. `transfer` need not outlive it.
class ClusterConstants {
 public:
  ClusterConstants(const CompressedTransfer& transfer, int rows);

  // Floats of every cluster's constants, and bytes of the panels' copy, for
  // a transfer read with `rows` exit rows: what a caller weighs before
  // making one. Like the constructor, they refuse a transfer whose cluster
  // data does not have the sizes it claims.
  static std::int64_t floats_for(const CompressedTransfer& transfer, int rows);
  static std::int64_t bytes_for(const CompressedTransfer& transfer, int rows);

  // Where cluster k's constants start in compute()'s buffer: stored vector
  // i's row r, channel c at begin(k) + 3 (rows i + r) + c.
  std::int64_t begin(Eigen::Index k) const { return begin_[std::size_t(k)]; }
  // Every cluster's constants into `out` (resized to whole panels).
  void compute(const Eigen::MatrixX3f& light, std::vector<float>& out) const;

 private:
  Eigen::Index n_i_ = 0;
  std::int64_t panel_count_ = 0;
  std::vector<std::int64_t> begin_;                             // clusters + 1
  std::vector<float, Eigen::aligned_allocator<float>> panels_;  // 64-byte aligned: whole packets
};

class RelightKernel {
 public:
  // Each stored vector is read as a `rows` x N_i matrix (rows = 1: diffuse).
  // `transfer` must outlive the kernel and stay unchanged.
  RelightKernel(const CompressedTransfer& transfer, int rows);

  int rows() const { return rows_; }
  // Whether one pass computes every cluster's constants for the parts to
  // share (from panels), or each part its own runs' (very many clusters).
  bool shares_constants() const { return shared_.has_value(); }
  const CompressedTransfer& transfer() const { return *transfer_; }

  // v x 3 radiance in mesh order: e_p . l for diffuse transfer (exit_values
  // null, rows 1); y(v_p) . e_p for glossy (exit_values v x rows).
  Eigen::MatrixX3f radiance(const Eigen::MatrixX3d& light,
                            const MatrixXfRow* exit_values = nullptr) const;
  // The same into `out` (resized; its storage reused frame after frame).
  void radiance(const Eigen::MatrixX3d& light, const MatrixXfRow* exit_values,
                Eigen::MatrixX3f& out) const;
  // v x 3 rows exit coefficients, RGB interleaved (e_p(i, c) at 3 i + c).
  MatrixXfRow exit_coefficients(const Eigen::MatrixX3d& light) const;

  // Bytes a frame must move at least: every per-vertex weight and cluster
  // index read, the exit values read (glossy), three floats written per
  // vertex. The bound the relight benchmark compares against.
  double streamed_bytes(bool with_exit_values) const;

 private:
  // Per part and cluster: its constants, then sums(k, constants, vertices,
  // size, weights, scratch) with `scratch_floats` floats of per-task scratch.
  template <class Sums>
  void for_each_cluster(const Eigen::MatrixX3f& light, std::size_t scratch_floats,
                        const Sums& sums) const;

  // A contiguous range of mesh vertices, relit by one task: results are
  // written straight to mesh order, each task to its own range (no second
  // pass to reorder them, no cache line written by two cores but at the
  // ranges' ends).
  struct Run {  // the part's vertices of one cluster
    std::int32_t cluster;
    std::int64_t begin, size;  // into vertices
    std::int64_t weights;      // into weights: n'_k x size, component-major
  };
  struct Part {
    std::vector<std::int32_t> vertices;  // the range's vertices sorted by cluster (stable)
    std::vector<Run> runs;
    std::vector<float, Eigen::aligned_allocator<float>>
        weights;  // n'_k per vertex, compact, then 16 floats of padding
  };

  const CompressedTransfer* transfer_;
  int rows_;
  std::vector<Part> parts_;
  // When every cluster's constants fit a small shared buffer (and their
  // panels a moderate one): computed in one pass for the parts to share.
  // Empty otherwise (each part computes its own runs' constants from the
  // transfer).
  std::optional<ClusterConstants> shared_;
  // The constants of the last frame's clusters, reused by the next (a fresh
  // buffer per frame would cost page faults for glossy transfer).
  struct Scratch {
    std::mutex mutex;
    std::vector<float> constants;
  };
  std::unique_ptr<Scratch> scratch_ = std::make_unique<Scratch>();
};

// One-off forms of the kernel (it is laid out on each call; a loop over
// frames keeps a RelightKernel instead).
// Per-vertex exit radiance (v x 3, linear RGB) for a light vector (n x 3):
// per-cluster constants c_ki = M_ki . l, then e_p = c_k0 + sum_i w_pi c_ki;
// for glossy transfer then y(v_p) . e_p with the exit basis's values toward
// the camera (v x N_r). The one relight path of every renderer.
Eigen::MatrixX3f relight(const CompressedTransfer& transfer, const Eigen::MatrixX3d& light,
                         const MatrixXfRow* exit_values = nullptr);

// Exit radiance y(v_p) . e_p per vertex (v x 3) from exit coefficients
// (v x 3 N_r, as exit_coefficients returns) and exit values (v x N_r).
Eigen::MatrixX3f exit_radiance(const MatrixXfRow& coefficients, const MatrixXfRow& values);

// The per-cluster constants of Sloan 2003 §6 (CPU side of rendering): for
// each cluster k a (n'_k + 1) x 3 rows matrix, row 0 = M_k0 l, row i = M_ki l,
// each stored vector read as a `rows` x N_i matrix (RGB interleaved).
std::vector<MatrixXfRow> cluster_constants(const CompressedTransfer& transfer,
                                           const Eigen::MatrixX3d& light, int rows);

// Exit-radiance coefficients per vertex for a light vector (N_i x 3), with
// each stored vector read as a `rows` x N_i matrix: per-cluster constants
// C_ki = M_ki l (rows x 3), then e_p = C_k0 + sum_i w_pi C_ki. Returns
// v x 3 rows, RGB interleaved per coefficient (e_p(i, c) at 3 i + c).
MatrixXfRow exit_coefficients(const CompressedTransfer& transfer, const Eigen::MatrixX3d& light,
                              int rows);

}  // namespace prt
