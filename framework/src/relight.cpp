#include "prt/relight.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <mutex>
#include <numeric>

#include "prt/error.hpp"

namespace prt {

namespace {

using Rows3 = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;

// Vertices of one cluster handled together: small enough for the partial sums
// to stay in registers / L1, large enough for the loops to vectorise.
constexpr int kBlock = 64;

void check_light(const CompressedTransfer& t, const Eigen::MatrixX3d& light, int rows) {
  const Eigen::Index n_i = light.rows();
  if (rows < 1 || n_i * rows != t.dimension)
    throw Error("light vector has " + std::to_string(n_i) + " coefficients, but the transfer's " +
                std::to_string(t.dimension) + " do not form " + std::to_string(rows) + " rows of " +
                std::to_string(n_i));
}

// constants(i, 3 r + c) = (vector_i read as rows x N_i) l, for the cluster's
// mean (i = 0) and its n'_k representatives, into `out` ((n'_k + 1) rows x 3
// rows).
void cluster_constants_into(const CompressedTransfer& t, Eigen::Index k, int rows,
                            const Eigen::MatrixX3f& l, float* out) {
  const Eigen::Index n_i = l.rows();
  const int n_k = t.components_of(k);
  // Each stored row dotted with the light's three contiguous channels (one
  // vectorised dot each, the row staying in L1): a lazy product of a dynamic
  // row-major matrix with a column-major one did not vectorise, and the
  // constants took most of a frame.
  using Vector = Eigen::Map<const Eigen::VectorXf>;
  const Vector red(l.col(0).data(), n_i), green(l.col(1).data(), n_i), blue(l.col(2).data(), n_i);
  const auto rows_into = [&](const float* stored, Eigen::Index count, float* into) {
    for (Eigen::Index r = 0; r < count; ++r) {
      const Vector row(stored + r * n_i, n_i);
      into[3 * r] = row.dot(red);
      into[3 * r + 1] = row.dot(green);
      into[3 * r + 2] = row.dot(blue);
    }
  };
  rows_into(t.means.row(k).data(), rows, out);
  // Row-major n'_k x (rows N_i) is the same memory as (n'_k rows) x N_i.
  if (n_k > 0) rows_into(t.representatives[k].data(), Eigen::Index(n_k) * rows, out + 3 * rows);
}

// out_c[j] = C_0c + sum_i w_i[j] C_ic for `count` <= kBlock vertices whose
// weights are stored component-major (w_i at weights + i * stride). N >= 0
// fixes n' at compile time so that the loops unroll; N = -1 reads n_dyn.
template <int N>
void diffuse_block(const float* constants, const float* weights, std::int64_t stride, int n_dyn,
                   int count, float* r, float* g, float* b) {
  const int n = N >= 0 ? N : n_dyn;
  for (int j = 0; j < count; ++j) {
    r[j] = constants[0];
    g[j] = constants[1];
    b[j] = constants[2];
  }
  for (int i = 0; i < n; ++i) {
    const float* w = weights + i * stride;
    const float cr = constants[3 * (i + 1)], cg = constants[3 * (i + 1) + 1],
                cb = constants[3 * (i + 1) + 2];
#pragma GCC ivdep
    for (int j = 0; j < count; ++j) {
      r[j] += w[j] * cr;
      g[j] += w[j] * cg;
      b[j] += w[j] * cb;
    }
  }
}

using DiffuseBlock = void (*)(const float*, const float*, std::int64_t, int, int, float*, float*,
                              float*);

DiffuseBlock diffuse_kernel(int n) {
  switch (n) {
    case 0:
      return diffuse_block<0>;
    case 1:
      return diffuse_block<1>;
    case 2:
      return diffuse_block<2>;
    case 3:
      return diffuse_block<3>;
    case 4:
      return diffuse_block<4>;
    case 6:
      return diffuse_block<6>;
    case 8:
      return diffuse_block<8>;
    case 12:
      return diffuse_block<12>;
    case 16:
      return diffuse_block<16>;
    default:
      return diffuse_block<-1>;
  }
}

}  // namespace

RelightKernel::RelightKernel(const CompressedTransfer& t, int rows) : transfer_(&t), rows_(rows) {
  if (rows < 1 || t.dimension % rows != 0)
    throw Error("relight: " + std::to_string(t.dimension) + " transfer coefficients do not form " +
                std::to_string(rows) + " exit rows");
  if (t.sparse()) return;  // no clusters to order
  const Eigen::Index clusters = t.clusters();
  // The layout indexes by these: refuse what validate() would (a bad index
  // here would be an out-of-bounds write).
  if (static_cast<Eigen::Index>(t.representatives.size()) != clusters ||
      t.weights.rows() != t.vertices())
    throw Error("relight: compressed transfer has inconsistent sizes");
  for (auto k : t.cluster_of_vertex)
    if (k < 0 || k >= clusters) throw Error("relight: cluster index out of range");
  for (Eigen::Index k = 0; k < clusters; ++k)
    if (t.components_of(k) > t.components || t.representatives[k].cols() != t.dimension)
      throw Error("relight: a representative block has the wrong size");
  cluster_begin_.assign(clusters + 1, 0);
  for (auto k : t.cluster_of_vertex) ++cluster_begin_[k + 1];
  std::partial_sum(cluster_begin_.begin(), cluster_begin_.end(), cluster_begin_.begin());
  vertex_order_.resize(t.cluster_of_vertex.size());
  std::vector<std::int64_t> next(cluster_begin_.begin(), cluster_begin_.end() - 1);
  for (std::size_t p = 0; p < t.cluster_of_vertex.size(); ++p)
    vertex_order_[next[t.cluster_of_vertex[p]]++] = static_cast<std::int32_t>(p);
  rank_.resize(vertex_order_.size());
  for (std::size_t j = 0; j < vertex_order_.size(); ++j)
    rank_[vertex_order_[j]] = static_cast<std::int32_t>(j);
  // Component-major weights per cluster: component i of the cluster's j-th
  // vertex at weight_begin_[k] + i * size_k + j, so sums vectorise over vertices.
  weight_begin_.assign(clusters + 1, 0);
  for (Eigen::Index k = 0; k < clusters; ++k)
    weight_begin_[k + 1] =
        weight_begin_[k] + (cluster_begin_[k + 1] - cluster_begin_[k]) * t.components_of(k);
  weights_.resize(static_cast<std::size_t>(weight_begin_.back()));
  tbb::parallel_for(Eigen::Index(0), clusters, [&](Eigen::Index k) {
    const std::int64_t size = cluster_begin_[k + 1] - cluster_begin_[k];
    const int n_k = t.components_of(k);
    for (std::int64_t j = 0; j < size; ++j) {
      const std::int32_t p = vertex_order_[cluster_begin_[k] + j];
      for (int i = 0; i < n_k; ++i) weights_[weight_begin_[k] + i * size + j] = t.weights(p, i);
    }
  });
}

void RelightKernel::to_mesh_order(const float* sorted, Eigen::MatrixX3f& out) const {
  float* red = out.col(0).data();
  float* green = out.col(1).data();
  float* blue = out.col(2).data();
  tbb::this_task_arena::isolate([&] {
    tbb::parallel_for(
        tbb::blocked_range<Eigen::Index>(0, out.rows(), 4096),
        [&](const auto& range) {
          for (Eigen::Index p = range.begin(); p < range.end(); ++p) {
            const float* rgb = sorted + 3 * std::size_t(rank_[p]);  // one cache line per vertex
            red[p] = rgb[0];
            green[p] = rgb[1];
            blue[p] = rgb[2];
          }
        },
        tbb::static_partitioner());
  });
}

template <class Sums>
void RelightKernel::for_each_cluster(const Eigen::MatrixX3f& l, std::size_t scratch_floats,
                                     const Sums& sums) const {
  const CompressedTransfer& t = *transfer_;
  const int width = 3 * rows_;  // floats of one stored vector's constant
  // One parallel pass (a second would cost a wake-up of the other cores per
  // frame): each cluster's constants, then its vertices' sums.
  // Isolated: a thread waiting here must not pick up an outer task that
  // relights this kernel again (its buffer is in use).
  tbb::this_task_arena::isolate([&] {
    tbb::parallel_for(
        tbb::blocked_range<Eigen::Index>(0, t.clusters()),
        [&](const auto& range) {
          // Buffers per task, sized for the largest cluster: no allocation per cluster.
          std::vector<float> constants(std::size_t(t.components + 1) * width);
          std::vector<float> scratch(scratch_floats);
          for (Eigen::Index k = range.begin(); k < range.end(); ++k) {
            const std::int64_t begin = cluster_begin_[k], size = cluster_begin_[k + 1] - begin;
            if (size == 0) continue;
            cluster_constants_into(t, k, rows_, l, constants.data());
            sums(k, constants.data(), vertex_order_.data() + begin, size,
                 weights_.data() + weight_begin_[k], scratch.data());
          }
        },
        tbb::static_partitioner());
  });
}

Eigen::MatrixX3f RelightKernel::radiance(const Eigen::MatrixX3d& light,
                                         const MatrixXfRow* exit_values) const {
  Eigen::MatrixX3f out;
  radiance(light, exit_values, out);
  return out;
}

void RelightKernel::radiance(const Eigen::MatrixX3d& light, const MatrixXfRow* exit_values,
                             Eigen::MatrixX3f& out) const {
  const CompressedTransfer& t = *transfer_;
  check_light(t, light, rows_);
  if (exit_values && (exit_values->cols() != rows_ || exit_values->rows() != t.vertices()))
    throw Error("relight: exit values are " + std::to_string(exit_values->rows()) + " x " +
                std::to_string(exit_values->cols()) + ", expected " + std::to_string(t.vertices()) +
                " x " + std::to_string(rows_));
  if (!exit_values && rows_ != 1)
    throw Error("relight: glossy transfer needs the exit basis's values toward the camera");
  if (t.sparse()) {
    out = exit_values ? exit_radiance(exit_coefficients(light), *exit_values)
                      : Eigen::MatrixX3f(Eigen::Map<const Rows3>(exit_coefficients(light).data(),
                                                                 t.vertices(), 3));
    return;
  }
  const Eigen::MatrixX3f l = light.cast<float>();
  // Sums are written in cluster order, RGB interleaved (each core writes its
  // own contiguous runs: cores share only the lines at run boundaries), then gathered
  // to mesh order (one cache line per vertex). The buffer is reused across
  // frames: no page faults of a fresh array each frame.
  // The kernel's own buffer when free; a caller relighting the same kernel
  // concurrently (or re-entrantly, from a task) gets a fresh one.
  std::unique_lock lock(scratch_->mutex, std::try_to_lock);
  std::vector<float> fresh;
  std::vector<float>& sorted_buffer = lock.owns_lock() ? scratch_->sorted : fresh;
  sorted_buffer.resize(3 * std::size_t(t.vertices()));
  float* sorted = sorted_buffer.data();
  out.resize(t.vertices(), 3);
  const std::int32_t* first = vertex_order_.data();
  if (!exit_values) {
    for_each_cluster(l, 0,
                     [&](Eigen::Index k, const float* constants, const std::int32_t* vertices,
                         std::int64_t size, const float* weights, float*) {
                       const int n_k = t.components_of(k);
                       const DiffuseBlock block = diffuse_kernel(n_k);
                       const std::int64_t at = vertices - first;
                       alignas(64) float r[kBlock], g[kBlock], b[kBlock];
                       for (std::int64_t j0 = 0; j0 < size; j0 += kBlock) {
                         const int count =
                             static_cast<int>(std::min<std::int64_t>(kBlock, size - j0));
                         block(constants, weights + j0, size, n_k, count, r, g, b);
                         float* rgb = sorted + 3 * (at + j0);
                         for (int j = 0; j < count; ++j) {
                           rgb[3 * j] = r[j];
                           rgb[3 * j + 1] = g[j];
                           rgb[3 * j + 2] = b[j];
                         }
                       }
                     });
    to_mesh_order(sorted, out);
    return;
  }
  // Glossy, fused: d_i(p) = y(v_p) . C_i (3 floats per stored vector) for a
  // block of vertices as one small product, then d_0 + sum_i w_pi d_i.
  const MatrixXfRow& y = *exit_values;
  const Eigen::Index most = t.components + 1;  // stored vectors of the largest cluster
  const std::size_t scratch = std::size_t(rows_ * 3 * most + kBlock * rows_ + kBlock * 3 * most);
  for_each_cluster(
      l, scratch,
      [&](Eigen::Index k, const float* constants, const std::int32_t* vertices, std::int64_t size,
          const float* weights, float* buffer) {
        const int n_k = t.components_of(k);
        const Eigen::Index vectors = n_k + 1;
        // C as N_r x 3 (n'_k + 1): column 3 i + c is C_i's channel c.
        Eigen::Map<MatrixXfRow> c_by_row(buffer, rows_, 3 * vectors);
        Eigen::Map<MatrixXfRow> y_block(buffer + rows_ * 3 * most, kBlock, rows_);
        Eigen::Map<MatrixXfRow> d(buffer + rows_ * 3 * most + kBlock * rows_, kBlock, 3 * vectors);
        for (Eigen::Index i = 0; i < vectors; ++i)
          c_by_row.middleCols<3>(3 * i) =
              Eigen::Map<const Rows3>(constants + 3 * rows_ * i, rows_, 3);
        for (std::int64_t j0 = 0; j0 < size; j0 += kBlock) {
          const int count = static_cast<int>(std::min<std::int64_t>(kBlock, size - j0));
          for (int j = 0; j < count; ++j) y_block.row(j) = y.row(vertices[j0 + j]);
          d.topRows(count).noalias() = y_block.topRows(count) * c_by_row;
          for (int j = 0; j < count; ++j) {
            float s[3] = {d(j, 0), d(j, 1), d(j, 2)};
            for (int i = 0; i < n_k; ++i) {
              const float w = weights[i * size + j0 + j];
              for (int c = 0; c < 3; ++c) s[c] += w * d(j, 3 * (i + 1) + c);
            }
            float* rgb = sorted + 3 * (vertices - first + j0 + j);
            rgb[0] = s[0];
            rgb[1] = s[1];
            rgb[2] = s[2];
          }
        }
      });
  to_mesh_order(sorted, out);
}

MatrixXfRow RelightKernel::exit_coefficients(const Eigen::MatrixX3d& light) const {
  const CompressedTransfer& t = *transfer_;
  check_light(t, light, rows_);
  const Eigen::Index n_i = light.rows();
  const Eigen::MatrixX3f l = light.cast<float>();
  MatrixXfRow out(t.vertices(), 3 * rows_);
  if (t.sparse()) {  // sparse products with the full light vector
    Eigen::RowVectorXf base(3 * rows_);
    Eigen::Map<Rows3>(base.data(), rows_, 3).noalias() =
        Eigen::Map<const MatrixXfRow>(t.means.row(0).data(), rows_, n_i) * l;
    tbb::parallel_for(Eigen::Index(0), t.vertices(), [&](Eigen::Index p) {
      Eigen::RowVectorXf e = base;
      for (int j = 0; j < t.components; ++j) {
        const int index = t.weight_index[p * t.components + j];
        const int row = static_cast<int>(index / n_i), column = static_cast<int>(index % n_i);
        e.segment<3>(3 * row) += t.weights(p, j) * l.row(column);
      }
      out.row(p) = e;
    });
    return out;
  }
  const int width = 3 * rows_;
  for_each_cluster(l, 0,
                   [&](Eigen::Index k, const float* constants, const std::int32_t* vertices,
                       std::int64_t size, const float* weights, float*) {
                     const int n_k = t.components_of(k);
                     for (std::int64_t j = 0; j < size; ++j) {
                       float* e = out.row(vertices[j]).data();
                       std::copy(constants, constants + width, e);
                       for (int i = 0; i < n_k; ++i) {
                         const float w = weights[i * size + j];
                         const float* c = constants + (i + 1) * width;
                         for (int q = 0; q < width; ++q) e[q] += w * c[q];
                       }
                     }
                   });
  return out;
}

double RelightKernel::streamed_bytes(bool with_exit_values) const {
  const CompressedTransfer& t = *transfer_;
  // Weights as stored compactly (n'_k per vertex), not padded to the largest n'.
  const double weights = t.sparse() ? double(t.weights.size()) : double(weights_.size());
  double bytes = weights * sizeof(float) +
                 double(t.cluster_of_vertex.size()) * sizeof(std::int32_t) +
                 double(t.vertices()) * 3 * sizeof(float);
  if (t.sparse()) bytes += double(t.weight_index.size()) * sizeof(std::int32_t);
  if (with_exit_values) bytes += double(t.vertices()) * rows_ * sizeof(float);
  return bytes;
}

Eigen::MatrixX3f exit_radiance(const MatrixXfRow& coefficients, const MatrixXfRow& values) {
  const Eigen::Index rows = values.cols();
  if (coefficients.cols() != 3 * rows || coefficients.rows() != values.rows())
    throw Error("exit radiance: coefficients do not match the exit basis and vertices");
  Eigen::MatrixX3f out(coefficients.rows(), 3);
  tbb::parallel_for(Eigen::Index(0), coefficients.rows(), [&](Eigen::Index p) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (Eigen::Index i = 0; i < rows; ++i)
      for (int c = 0; c < 3; ++c) sum[c] += double(values(p, i)) * coefficients(p, 3 * i + c);
    out.row(p) = sum.cast<float>().transpose();
  });
  return out;
}

Eigen::MatrixX3f relight(const CompressedTransfer& t, const Eigen::MatrixX3d& light,
                         const MatrixXfRow* exit_values) {
  const int rows = exit_values ? static_cast<int>(exit_values->cols()) : 1;
  return RelightKernel(t, rows).radiance(light, exit_values);
}

MatrixXfRow exit_coefficients(const CompressedTransfer& t, const Eigen::MatrixX3d& light,
                              int rows) {
  return RelightKernel(t, rows).exit_coefficients(light);
}

std::vector<MatrixXfRow> cluster_constants(const CompressedTransfer& t,
                                           const Eigen::MatrixX3d& light, int rows) {
  check_light(t, light, rows);
  if (t.sparse()) throw Error("cluster_constants: a sparse transfer has no clusters");
  const Eigen::MatrixX3f l = light.cast<float>();
  std::vector<MatrixXfRow> constants(t.clusters());
  tbb::parallel_for(Eigen::Index(0), t.clusters(), [&](Eigen::Index k) {
    constants[k].resize(t.components_of(k) + 1, 3 * rows);
    cluster_constants_into(t, k, rows, l, constants[k].data());
  });
  return constants;
}

}  // namespace prt
