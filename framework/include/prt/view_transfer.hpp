// Glossy transfer seen from one camera, folded into the light's space.
//
// A glossy relight with per-cluster constants (RelightKernel) costs each
// vertex (n'_k + 1) x N_r x 3 multiply-adds a frame, whatever changed: more
// than streaming its bytes takes (docs/performance.md, "Glossy CPU relight").
// While the camera stays put, the exit basis's values toward it y(v_p) do
// not change, so neither does the vertex's light-space vector
//
//   t_p = M_p^T y(v_p),   M_p = M_k0 + sum_j w_pj M_kj   (N_r x n_L each),
//
// and a light change costs t_p . l per channel: n_L x 3 multiply-adds and
// n_L floats read per vertex. A camera change rebuilds every t_p (one small
// product per cluster, ~(n'_k + 1) N_r n_L multiply-adds a vertex). Results
// equal RelightKernel::radiance's to float rounding (the sums run in
// another order).
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "prt/transfer.hpp"

namespace prt {

class ViewTransfer {
 public:
  // `transfer`: glossy transfer, each stored vector a `exit_values.cols()` x
  // n_L matrix (one channel group); `exit_values`: v x N_r, the exit basis
  // toward the camera at each vertex. Throws prt::Error when their sizes
  // disagree. Neither needs to outlive it.
  ViewTransfer(const CompressedTransfer& transfer, const MatrixXfRow& exit_values);

  Eigen::Index vertices() const { return vertices_; }
  Eigen::Index light_size() const { return light_size_; }
  // v x n_L: row p is t_p (a copy, unpacked: for tests and tools).
  MatrixXfRow light_space() const;

  // Throws prt::Error unless `light` is a finite n_L x 3 array.
  void check_light(const Eigen::MatrixX3d& light) const;
  // v x 3 radiance toward the camera for a light vector (n_L x 3) into `out`
  // (resized; its storage reused frame after frame).
  void radiance(const Eigen::MatrixX3d& light, Eigen::MatrixX3f& out) const;
  Eigen::MatrixX3f radiance(const Eigen::MatrixX3d& light) const;

  // Bytes a light change must move at least: every t_p read, three floats
  // written per vertex. The bound the relight benchmark compares against.
  double streamed_bytes() const;

 private:
  Eigen::Index vertices_ = 0, light_size_ = 0;
  // Packets of 16 vertices in mesh order, each n_L x 16 (coefficient i of
  // the packet's vertex j at 16 i + j; the last packet padded with zeros), so
  // that a frame reads them once, front to back, 16 vertices per vector op.
  std::vector<float, Eigen::aligned_allocator<float>> packets_;
};

}  // namespace prt
