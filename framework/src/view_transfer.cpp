#include "prt/view_transfer.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstring>
#include <string>

#include "prt/error.hpp"

namespace prt {
namespace {

// 16 floats in registers (GCC vector extension: AVX-512 where built for it).
typedef float Lanes __attribute__((vector_size(64)));
constexpr int kLanes = 16;
// Vertices of one cluster folded by one product (bounds its scratch).
constexpr Eigen::Index kBlock = 512;

using RowMap = Eigen::Map<const MatrixXfRow>;

Lanes load_lanes(const float* p) {
  Lanes v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

void check_sizes(const CompressedTransfer& t, const MatrixXfRow& exit_values) {
  const Eigen::Index rows = exit_values.cols();
  if (exit_values.rows() != t.vertices() || rows < 1 || t.dimension % rows != 0)
    throw Error("view transfer: exit values are " + std::to_string(exit_values.rows()) + " x " +
                std::to_string(rows) + ", which does not fit " + std::to_string(t.vertices()) +
                " vertices of " + std::to_string(t.dimension) + " coefficients");
  t.validate(t.vertices(), false);
}

// Vertices grouped by cluster, each group in mesh order: `order` and where
// each cluster's group begins in it (clusters + 1).
void group_by_cluster(const CompressedTransfer& t, std::vector<std::int32_t>& order,
                      std::vector<Eigen::Index>& begin) {
  begin.assign(std::size_t(t.clusters()) + 1, 0);
  for (const std::int32_t k : t.cluster_of_vertex) ++begin[std::size_t(k) + 1];
  for (std::size_t k = 1; k < begin.size(); ++k) begin[k] += begin[k - 1];
  std::vector<Eigen::Index> next(begin.begin(), begin.end() - 1);
  order.resize(t.cluster_of_vertex.size());
  for (std::size_t p = 0; p < order.size(); ++p)
    order[std::size_t(next[std::size_t(t.cluster_of_vertex[p])]++)] = std::int32_t(p);
}

}  // namespace

ViewTransfer::ViewTransfer(const CompressedTransfer& t, const MatrixXfRow& y) {
  check_sizes(t, y);
  const Eigen::Index rows = y.cols();
  vertices_ = t.vertices();
  light_size_ = t.dimension / rows;
  const Eigen::Index n_l = light_size_;
  const Eigen::Index packets = (vertices_ + kLanes - 1) / kLanes;
  packets_.assign(std::size_t(packets * n_l * kLanes), 0.f);
  auto store = [&](Eigen::Index p, const float* t_p) {
    float* packet = packets_.data() + (p / kLanes) * n_l * kLanes + p % kLanes;
    for (Eigen::Index i = 0; i < n_l; ++i) packet[i * kLanes] = t_p[i];
  };
  if (t.sparse()) {  // t_p = M_0^T y_p + sum_j w_pj y_p(row_j) e_(column_j)
    const RowMap base(t.means.row(0).data(), rows, n_l);
    tbb::parallel_for(Eigen::Index(0), vertices_, [&](Eigen::Index p) {
      Eigen::RowVectorXf t_p = y.row(p) * base;
      for (int j = 0; j < t.components; ++j) {
        const int index = t.weight_index[std::size_t(p * t.components + j)];
        t_p[index % n_l] += t.weights(p, j) * y(p, index / n_l);
      }
      store(p, t_p.data());
    });
    return;
  }
  // Per cluster, a block of its vertices at a time:
  // T = Y M_k0 + [w_1 Y | ... | w_n' Y] [M_k1; ...; M_kn'].
  std::vector<std::int32_t> order;
  std::vector<Eigen::Index> begin;
  group_by_cluster(t, order, begin);
  tbb::parallel_for(Eigen::Index(0), t.clusters(), [&](Eigen::Index k) {
    const int n_k = t.components_of(k);
    const RowMap mean(t.means.row(k).data(), rows, n_l);
    const RowMap representatives(t.representatives[std::size_t(k)].data(), n_k * rows, n_l);
    MatrixXfRow values, weighted, folded;
    for (Eigen::Index b = begin[std::size_t(k)]; b < begin[std::size_t(k) + 1]; b += kBlock) {
      const Eigen::Index size = std::min(kBlock, begin[std::size_t(k) + 1] - b);
      values.resize(size, rows);
      weighted.resize(size, n_k * rows);
      for (Eigen::Index j = 0; j < size; ++j) {
        const Eigen::Index p = order[std::size_t(b + j)];
        values.row(j) = y.row(p);
        for (int i = 0; i < n_k; ++i)
          weighted.row(j).segment(i * rows, rows) = t.weights(p, i) * y.row(p);
      }
      folded.noalias() = values * mean;
      if (n_k > 0) folded.noalias() += weighted * representatives;
      for (Eigen::Index j = 0; j < size; ++j)
        store(order[std::size_t(b + j)], folded.row(j).data());
    }
  });
}

MatrixXfRow ViewTransfer::light_space() const {
  MatrixXfRow out(vertices_, light_size_);
  for (Eigen::Index p = 0; p < vertices_; ++p)
    for (Eigen::Index i = 0; i < light_size_; ++i)
      out(p, i) =
          packets_[std::size_t((p / kLanes) * light_size_ * kLanes + i * kLanes + p % kLanes)];
  return out;
}

void ViewTransfer::check_light(const Eigen::MatrixX3d& light) const {
  if (light.rows() != light_size_ || !light.allFinite())
    throw Error("view transfer: the light must be a finite " + std::to_string(light_size_) +
                " x 3 array, not " + std::to_string(light.rows()) + " x 3");
}

void ViewTransfer::radiance(const Eigen::MatrixX3d& light, Eigen::MatrixX3f& out) const {
  check_light(light);
  const Eigen::MatrixX3f l = light.cast<float>();
  out.resize(vertices_, 3);
  const Eigen::Index n_l = light_size_;
  const Eigen::Index packets = (vertices_ + kLanes - 1) / kLanes;
  // Each lane sums its own vertex's products in a fixed order: a vertex's
  // result does not depend on how the packets are split over the cores.
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, packets, 64), [&](const auto& range) {
    for (Eigen::Index q = range.begin(); q < range.end(); ++q) {
      const float* packet = packets_.data() + q * n_l * kLanes;
      Lanes rgb[3] = {};
      for (Eigen::Index i = 0; i < n_l; ++i) {
        const Lanes t_i = load_lanes(packet + i * kLanes);
        for (int c = 0; c < 3; ++c) rgb[c] += t_i * l(i, c);
      }
      const Eigen::Index first = q * kLanes;
      const Eigen::Index count = std::min<Eigen::Index>(kLanes, vertices_ - first);
      for (int c = 0; c < 3; ++c)
        std::memcpy(out.col(c).data() + first, &rgb[c], std::size_t(count) * sizeof(float));
    }
  });
}

Eigen::MatrixX3f ViewTransfer::radiance(const Eigen::MatrixX3d& light) const {
  Eigen::MatrixX3f out;
  radiance(light, out);
  return out;
}

double ViewTransfer::streamed_bytes() const {
  return double(packets_.size()) * sizeof(float) + double(vertices_) * 3 * sizeof(float);
}

}  // namespace prt
