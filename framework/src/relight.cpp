#include "prt/relight.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstring>
#include <mutex>
#include <numeric>

#include "prt/error.hpp"

namespace prt {

namespace {

using Rows3 = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;

void check_light(const CompressedTransfer& t, const Eigen::MatrixX3d& light, int rows) {
  const Eigen::Index n_i = light.rows();
  if (rows < 1 || n_i * rows != t.dimension)
    throw Error("light vector has " + std::to_string(n_i) + " coefficients, but the transfer's " +
                std::to_string(t.dimension) + " do not form " + std::to_string(rows) + " rows of " +
                std::to_string(n_i));
}

// 16 floats in registers (GCC vector extension: AVX-512 where built for it).
typedef float Lanes __attribute__((vector_size(64)));
constexpr int kLanes = 16;

// Above this, the parts compute their own clusters' constants (see the constructor).
constexpr std::int64_t kSharedConstantsBytes = std::int64_t(4) << 20;
// ... and while the cluster data's copy in panels stays below this.
constexpr std::int64_t kPanelBytes = std::int64_t(64) << 20;

Lanes load_lanes(const float* p) {
  Lanes v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

// Sum of the lanes by halving (4 shuffles and adds, not a chain of 15).
float sum_lanes(Lanes v) {
  typedef int Indices __attribute__((vector_size(64)));
  v += __builtin_shuffle(v, Indices{8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3, 4, 5, 6, 7});
  v += __builtin_shuffle(v, Indices{4, 5, 6, 7, 0, 1, 2, 3, 4, 5, 6, 7, 0, 1, 2, 3});
  v += __builtin_shuffle(v, Indices{2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1});
  v += __builtin_shuffle(v, Indices{1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0});
  return v[0];
}

// into[3 r + c] = row r of `stored` (count rows of n_i floats) . light
// channel c, for `Group` rows at a time: the group's 3 Group sums stay in
// registers while the light's three channels stream past once per group
// (three separate dots per row read the row three times and reduced each
// sum across lanes on its own).
template <int Group>
void light_dots_group(const float* stored, Eigen::Index n_i, const float* red, const float* green,
                      const float* blue, float* into) {
  Lanes sums[Group][3] = {};
  Eigen::Index d = 0;
  for (; d + kLanes <= n_i; d += kLanes) {
    const Lanes r = load_lanes(red + d), g = load_lanes(green + d), b = load_lanes(blue + d);
    for (int q = 0; q < Group; ++q) {
      const Lanes m = load_lanes(stored + q * n_i + d);
      sums[q][0] += m * r;
      sums[q][1] += m * g;
      sums[q][2] += m * b;
    }
  }
  for (int q = 0; q < Group; ++q) {
    float tail[3] = {0, 0, 0};
    for (Eigen::Index e = d; e < n_i; ++e) {
      const float m = stored[q * n_i + e];
      tail[0] += m * red[e];
      tail[1] += m * green[e];
      tail[2] += m * blue[e];
    }
    for (int c = 0; c < 3; ++c) into[3 * q + c] = sum_lanes(sums[q][c]) + tail[c];
  }
}

void light_dots(const float* stored, Eigen::Index count, Eigen::Index n_i, const float* red,
                const float* green, const float* blue, float* into) {
  Eigen::Index r = 0;
  for (; r + 4 <= count; r += 4)
    light_dots_group<4>(stored + r * n_i, n_i, red, green, blue, into + 3 * r);
  for (; r < count; ++r) light_dots_group<1>(stored + r * n_i, n_i, red, green, blue, into + 3 * r);
}

// The stored rows of every cluster (its mean's `rows` rows, then its
// representatives'), 16 to a panel and laid out d-major (panel[16 d + j] is
// row j's d-th float), so that 16 rows' dots with the light vectorise over
// the rows: each float of cluster data is one multiply-add per channel with a
// broadcast light value, no sums reduced across lanes and no tail (the
// row-major dots above read each row in packets and reduce 3 sums per row).
constexpr int kPanelRows = kLanes;

// into[3 j + c] = lane j of rgb[c] for the 16 lanes: three packets, each
// from two two-source shuffles (element e of the 48 is channel e % 3 of lane
// e / 3; red and green first, then blue into the places kept for it). Scalar
// stores through a zeroed stack array: the pass took ~3% longer (9.56-9.77
// against 9.42-9.50 us for the bunny's 256 x 8).
void store_interleaved(const Lanes rgb[3], float* into) {
  typedef int Indices __attribute__((vector_size(64)));
  static constexpr Indices kRedGreen[3] = {
      {0, 16, 0, 1, 17, 0, 2, 18, 0, 3, 19, 0, 4, 20, 0, 5},
      {21, 0, 6, 22, 0, 7, 23, 0, 8, 24, 0, 9, 25, 0, 10, 26},
      {0, 11, 27, 0, 12, 28, 0, 13, 29, 0, 14, 30, 0, 15, 31, 0}};
  static constexpr Indices kBlue[3] = {{0, 1, 16, 3, 4, 17, 6, 7, 18, 9, 10, 19, 12, 13, 20, 15},
                                       {0, 21, 2, 3, 22, 5, 6, 23, 8, 9, 24, 11, 12, 25, 14, 15},
                                       {26, 1, 2, 27, 4, 5, 28, 7, 8, 29, 10, 11, 30, 13, 14, 31}};
  for (int v = 0; v < 3; ++v) {
    const Lanes packet =
        __builtin_shuffle(__builtin_shuffle(rgb[0], rgb[1], kRedGreen[v]), rgb[2], kBlue[v]);
    std::memcpy(into + kLanes * v, &packet, sizeof packet);
  }
}

// into[48 q + 3 j + c] = row j of panel q . light channel c, for the
// `Group` panels from `panel` (3 Group sums in registers; six panels share
// each broadcast of the light's values: with store_interleaved, 8.8-8.9 us
// a frame for the bunny's 256 x 8 against 9.4-9.5 with three panels and
// scalar stores). A row's sum does not depend on the group.
template <int Group>
void panel_dots_group(const float* panel, Eigen::Index n_i, const float* red, const float* green,
                      const float* blue, float* into) {
  Lanes sums[Group][3] = {};
  for (Eigen::Index d = 0; d < n_i; ++d) {
    const float r = red[d], g = green[d], b = blue[d];
    for (int q = 0; q < Group; ++q) {
      const Lanes m = load_lanes(panel + (q * n_i + d) * kPanelRows);
      sums[q][0] += m * r;
      sums[q][1] += m * g;
      sums[q][2] += m * b;
    }
  }
  for (int q = 0; q < Group; ++q) store_interleaved(sums[q], into + 3 * kPanelRows * q);
}

void panel_dots(const float* panels, Eigen::Index count, Eigen::Index n_i, const float* red,
                const float* green, const float* blue, float* into) {
  const Eigen::Index stride = n_i * kPanelRows;
  Eigen::Index q = 0;
  for (; q + 6 <= count; q += 6)
    panel_dots_group<6>(panels + q * stride, n_i, red, green, blue, into + 3 * kPanelRows * q);
  for (; q + 3 <= count; q += 3)
    panel_dots_group<3>(panels + q * stride, n_i, red, green, blue, into + 3 * kPanelRows * q);
  for (; q < count; ++q)
    panel_dots_group<1>(panels + q * stride, n_i, red, green, blue, into + 3 * kPanelRows * q);
}

// constants(i, 3 r + c) = (vector_i read as rows x N_i) l, for the cluster's
// mean (i = 0) and its n'_k representatives, into `out` ((n'_k + 1) rows x 3
// rows).
void cluster_constants_into(const CompressedTransfer& t, Eigen::Index k, int rows,
                            const Eigen::MatrixX3f& l, float* out) {
  const Eigen::Index n_i = l.rows();
  const int n_k = t.components_of(k);
  const float *red = l.col(0).data(), *green = l.col(1).data(), *blue = l.col(2).data();
  light_dots(t.means.row(k).data(), rows, n_i, red, green, blue, out);
  // Row-major n'_k x (rows N_i) is the same memory as (n'_k rows) x N_i.
  if (n_k > 0)
    light_dots(t.representatives[k].data(), Eigen::Index(n_k) * rows, n_i, red, green, blue,
               out + 3 * rows);
}

// red[vertices[q]] = lane q of rgb[0] (and green, blue) for all 16 lanes,
// named at compile time so that each store takes its lane from the register
// (through the stack, 48 scalar loads more per 16 vertices: the bunny's
// diffuse relight took 0.050-0.051 ms against 0.048-0.049).
template <int... Q>
inline void store_lanes(const Lanes rgb[3], const std::int32_t* vertices, float* red, float* green,
                        float* blue, std::integer_sequence<int, Q...>) {
  ((red[vertices[Q]] = rgb[0][Q], green[vertices[Q]] = rgb[1][Q], blue[vertices[Q]] = rgb[2][Q]),
   ...);
}

// The first `count` lanes of a packet's sums to mesh order: a full packet
// with store_lanes, a run's last partial one lane by lane.
inline void store_packet(const Lanes rgb[3], const std::int32_t* vertices, int count, float* red,
                         float* green, float* blue) {
  if (count == kLanes) {
    store_lanes(rgb, vertices, red, green, blue, std::make_integer_sequence<int, kLanes>());
    return;
  }
  alignas(64) float lanes[3][kLanes];
  std::memcpy(lanes, rgb, sizeof lanes);
  for (int q = 0; q < count; ++q) {
    const std::int32_t p = vertices[q];
    red[p] = lanes[0][q];
    green[p] = lanes[1][q];
    blue[p] = lanes[2][q];
  }
}

// red[v] = C_0r + sum_i w_i(v) C_ir (and green, blue) for the `size`
// vertices of one run, whose weights are stored component-major (w_i at
// weights + i * size): 16 vertices' three sums stay in registers over all n'
// components, then go straight to mesh order. N >= 0 fixes n' at compile
// time so that the loop unrolls; N = -1 reads n_dyn.
template <int N>
void diffuse_run(const float* constants, const float* weights, std::int64_t size, int n_dyn,
                 const std::int32_t* vertices, float* red, float* green, float* blue) {
  const int n = N >= 0 ? N : n_dyn;
  // The last packet reads past `size` into the next stored weights (the
  // weights end with kLanes floats of padding); its extra lanes are never
  // written.
  for (std::int64_t j = 0; j < size; j += kLanes) {
    Lanes sums[3] = {Lanes{} + constants[0], Lanes{} + constants[1], Lanes{} + constants[2]};
    for (int i = 0; i < n; ++i) {
      const Lanes w = load_lanes(weights + i * size + j);
      const float* c = constants + 3 * (i + 1);
      sums[0] += w * c[0];
      sums[1] += w * c[1];
      sums[2] += w * c[2];
    }
    store_packet(sums, vertices + j, static_cast<int>(std::min<std::int64_t>(kLanes, size - j)),
                 red, green, blue);
  }
}

using DiffuseRun = void (*)(const float*, const float*, std::int64_t, int, const std::int32_t*,
                            float*, float*, float*);

DiffuseRun diffuse_kernel(int n) {
  switch (n) {
    case 0:
      return diffuse_run<0>;
    case 1:
      return diffuse_run<1>;
    case 2:
      return diffuse_run<2>;
    case 3:
      return diffuse_run<3>;
    case 4:
      return diffuse_run<4>;
    case 6:
      return diffuse_run<6>;
    case 8:
      return diffuse_run<8>;
    case 12:
      return diffuse_run<12>;
    case 16:
      return diffuse_run<16>;
    default:
      return diffuse_run<-1>;
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
  // here would be an out-of-bounds read or write).
  if (static_cast<Eigen::Index>(t.representatives.size()) != clusters ||
      t.weights.rows() != t.vertices() || t.weights.cols() < t.components)
    throw Error("relight: compressed transfer has inconsistent sizes");
  for (auto k : t.cluster_of_vertex)
    if (k < 0 || k >= clusters) throw Error("relight: cluster index out of range");
  for (Eigen::Index k = 0; k < clusters; ++k)
    if (t.components_of(k) > t.components || t.representatives[k].cols() != t.dimension)
      throw Error("relight: a representative block has the wrong size");
  // One range per core, at least 4,096 vertices each (a task per range).
  // Results do not depend on the split.
  const Eigen::Index vertices = t.vertices();
  const Eigen::Index count = std::clamp<Eigen::Index>(
      std::min<Eigen::Index>(tbb::this_task_arena::max_concurrency(), vertices / 4096), 1, 256);
  parts_.resize(std::size_t(count));
  tbb::parallel_for(Eigen::Index(0), count, [&](Eigen::Index q) {
    Part& part = parts_[std::size_t(q)];
    const Eigen::Index first = vertices * q / count, last = vertices * (q + 1) / count;
    // The range's vertices by cluster, in mesh order within a cluster; runs
    // of one cluster each (at most one per vertex: a part's tables grow with
    // its vertices, not with the clusters, which the exact form has per vertex).
    part.vertices.resize(std::size_t(last - first));
    std::iota(part.vertices.begin(), part.vertices.end(), static_cast<std::int32_t>(first));
    std::stable_sort(
        part.vertices.begin(), part.vertices.end(), [&](std::int32_t a, std::int32_t b) {
          return t.cluster_of_vertex[std::size_t(a)] < t.cluster_of_vertex[std::size_t(b)];
        });
    std::int64_t weights = 0;
    for (std::size_t j = 0; j < part.vertices.size();) {
      const std::int32_t k = t.cluster_of_vertex[std::size_t(part.vertices[j])];
      std::size_t end = j;
      while (end < part.vertices.size() &&
             t.cluster_of_vertex[std::size_t(part.vertices[end])] == k)
        ++end;
      part.runs.push_back({k, std::int64_t(j), std::int64_t(end - j), weights});
      weights += std::int64_t(end - j) * t.components_of(k);
      j = end;
    }
    // Component i of a run's j-th vertex at run.weights + i * run.size + j, so
    // sums vectorise over vertices; kLanes floats of padding at the end, as
    // the sums read whole packets (diffuse_run).
    part.weights.assign(std::size_t(weights) + kLanes, 0.f);
    for (const Run& run : part.runs)
      for (int i = 0; i < t.components_of(run.cluster); ++i)
        for (std::int64_t j = 0; j < run.size; ++j)
          part.weights[std::size_t(run.weights + i * run.size + j)] =
              t.weights(part.vertices[std::size_t(run.begin + j)], i);
  });
  // One pass computes every cluster's constants for the parts to share,
  // unless that buffer or the panels' copy of the cluster data would be large
  // (many clusters, as the exact form's one per vertex): each part then
  // computes the constants of its own runs instead.
  if (ClusterConstants::floats_for(t, rows) * std::int64_t(sizeof(float)) <=
          kSharedConstantsBytes &&
      ClusterConstants::bytes_for(t, rows) <= kPanelBytes)
    shared_.emplace(t, rows);
}

namespace {

// Refuses what the panels would read out of bounds.
void check_cluster_data(const CompressedTransfer& t, int rows) {
  if (rows < 1 || t.dimension % rows != 0 || t.sparse())
    throw Error("cluster constants: the transfer has no clusters of " + std::to_string(rows) +
                " exit rows");
  bool consistent = t.means.cols() == t.dimension &&
                    static_cast<Eigen::Index>(t.representatives.size()) == t.clusters();
  for (std::size_t k = 0; consistent && k < t.representatives.size(); ++k)
    consistent = t.representatives[k].cols() == t.dimension;
  if (!consistent)
    throw Error("cluster constants: the transfer's cluster data has inconsistent sizes");
}

}  // namespace

std::int64_t ClusterConstants::floats_for(const CompressedTransfer& t, int rows) {
  check_cluster_data(t, rows);
  std::int64_t floats = 0;
  for (Eigen::Index k = 0; k < t.clusters(); ++k)
    floats += std::int64_t(t.components_of(k) + 1) * 3 * rows;
  return floats;
}

std::int64_t ClusterConstants::bytes_for(const CompressedTransfer& t, int rows) {
  const std::int64_t panels = (floats_for(t, rows) / 3 + kPanelRows - 1) / kPanelRows;
  return panels * kPanelRows * (t.dimension / rows) * std::int64_t(sizeof(float));
}

ClusterConstants::ClusterConstants(const CompressedTransfer& t, int rows) {
  check_cluster_data(t, rows);
  n_i_ = t.dimension / rows;
  const Eigen::Index clusters = t.clusters();
  begin_.assign(std::size_t(clusters) + 1, 0);
  for (Eigen::Index k = 0; k < clusters; ++k)
    begin_[std::size_t(k) + 1] =
        begin_[std::size_t(k)] + std::int64_t(t.components_of(k) + 1) * 3 * rows;
  panel_count_ = (begin_.back() / 3 + kPanelRows - 1) / kPanelRows;
  panels_.assign(std::size_t(panel_count_ * kPanelRows * n_i_), 0.f);  // zero rows pad the last
  tbb::parallel_for(Eigen::Index(0), clusters, [&](Eigen::Index k) {
    const std::int64_t first = begin_[std::size_t(k)] / 3;  // the cluster's first stored row
    const std::int64_t count = (begin_[std::size_t(k) + 1] - begin_[std::size_t(k)]) / 3;
    for (std::int64_t r = 0; r < count; ++r) {
      const float* row = r < rows ? t.means.row(k).data() + r * n_i_
                                  : t.representatives[std::size_t(k)].data() + (r - rows) * n_i_;
      float* panel = panels_.data() + (first + r) / kPanelRows * kPanelRows * n_i_;
      for (Eigen::Index d = 0; d < n_i_; ++d)
        panel[d * kPanelRows + (first + r) % kPanelRows] = row[d];
    }
  });
}

void ClusterConstants::compute(const Eigen::MatrixX3f& light, std::vector<float>& out) const {
  if (light.rows() != n_i_)
    throw Error("cluster constants: the light has " + std::to_string(light.rows()) +
                " coefficients, the clusters' stored rows " + std::to_string(n_i_));
  const Eigen::Index stride = n_i_ * kPanelRows;
  out.resize(
      std::size_t(panel_count_ * 3 * kPanelRows));  // whole panels: past begin_.back() unused
  const float *red = light.col(0).data(), *green = light.col(1).data(), *blue = light.col(2).data();
  tbb::parallel_for(
      tbb::blocked_range<Eigen::Index>(0, panel_count_),
      [&](const auto& range) {
        panel_dots(panels_.data() + range.begin() * stride, range.size(), n_i_, red, green, blue,
                   out.data() + 3 * kPanelRows * range.begin());
      },
      tbb::static_partitioner());
}

template <class Sums>
void RelightKernel::for_each_cluster(const Eigen::MatrixX3f& l, std::size_t scratch_floats,
                                     const Sums& sums) const {
  const CompressedTransfer& t = *transfer_;
  const int width = 3 * rows_;  // floats of one stored vector's constant
  const bool shared = shared_.has_value();
  // The kernel's own buffer when free; a caller relighting the same kernel
  // concurrently (or re-entrantly, from a task) gets a fresh one.
  std::unique_lock lock(scratch_->mutex, std::defer_lock);
  std::vector<float> fresh;
  std::vector<float>* constants = &fresh;
  if (shared && lock.try_lock()) constants = &scratch_->constants;
  // Shared constants: two parallel passes, every cluster's constants (16
  // stored rows at a time) split over the cores, then a task per part for
  // the sums. (Each part computing the constants of its own clusters
  // repeated them on every core for the bunny's CPCA: 0.15-0.18 ms a frame
  // against 0.105 ms.) Isolated: a thread waiting here must not pick up an
  // outer task that relights this kernel again.
  tbb::this_task_arena::isolate([&] {
    if (shared) shared_->compute(l, *constants);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, parts_.size(), 1),
        [&](const auto& range) {
          // Per task, not per cluster.
          std::vector<float> own(shared ? 0 : std::size_t(t.components + 1) * width);
          std::vector<float> scratch(scratch_floats);
          for (std::size_t q = range.begin(); q < range.end(); ++q) {
            const Part& part = parts_[q];
            for (const Run& run : part.runs) {
              const float* c = constants->data();
              if (shared) {
                c += shared_->begin(run.cluster);
              } else {
                cluster_constants_into(t, run.cluster, rows_, l, own.data());
                c = own.data();
              }
              sums(Eigen::Index(run.cluster), c, part.vertices.data() + run.begin, run.size,
                   part.weights.data() + run.weights, scratch.data());
            }
          }
        },
        tbb::static_partitioner());
  });
}

namespace {

// One cluster's vertices: the per-cluster constants C_i (N_r x 3 per stored
// vector), its vertices and their weights (n'_k per vertex, cluster-major).
struct ClusterInput {
  const float* constants;
  const std::int32_t* vertices;
  std::int64_t size;
  const float* weights;
  int components;
};

constexpr int kDotGroup = 8;  // dots kept in registers at once

// Glossy, fused: d_i(p) = y(v_p) . C_i (3 floats per stored vector), then
// d_0 + sum_i w_pi d_i, for 16 vertices at a time, one per lane: each lane
// sums over its own exit values in a fixed order, so a vertex's result does
// not depend on which vertices share its packet (a block product rounds a
// row by the block's shape, and the blocks depend on how the mesh is split).
void glossy_cluster(const ClusterInput& in, int rows, const MatrixXfRow& y, float* buffer,
                    float* red, float* green, float* blue) {
  const int n_k = in.components;
  const Eigen::Index width = (3 * (n_k + 1) + kDotGroup - 1) / kDotGroup * kDotGroup;
  // C as N_r x 3 (n'_k + 1), padded with zero columns to whole groups:
  // column 3 i + c is C_i's channel c.
  float* c_by_row = buffer;
  float* lanes = buffer + rows * width;              // N_r x 16: lane j is vertex j's values
  float* dots = lanes + std::size_t(rows) * kLanes;  // width x 16
  std::fill(c_by_row, c_by_row + rows * width, 0.f);
  for (int i = 0; i <= n_k; ++i)
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < 3; ++c)
        c_by_row[r * width + 3 * i + c] = in.constants[3 * rows * i + 3 * r + c];
  for (std::int64_t j0 = 0; j0 < in.size; j0 += kLanes) {
    const int count = static_cast<int>(std::min<std::int64_t>(kLanes, in.size - j0));
    // The next packet's exit values (rows scattered over the mesh):
    // requested now, they arrive while this packet's dots run.
    for (std::int64_t j = j0 + kLanes; j < std::min<std::int64_t>(in.size, j0 + 2 * kLanes); ++j) {
      const char* next = reinterpret_cast<const char*>(y.row(in.vertices[j]).data());
      for (int line = 0; line < rows * int(sizeof(float)); line += 64)
        __builtin_prefetch(next + line);
    }
    for (int j = 0; j < kLanes; ++j) {
      const float* values = y.row(in.vertices[j0 + std::min(j, count - 1)]).data();
      for (int r = 0; r < rows; ++r) lanes[r * kLanes + j] = values[r];
    }
    for (Eigen::Index o = 0; o < width; o += kDotGroup) {
      Lanes sums[kDotGroup] = {};
      for (int r = 0; r < rows; ++r) {
        const Lanes e = load_lanes(lanes + r * kLanes);
        const float* c = c_by_row + r * width + o;
        for (int g = 0; g < kDotGroup; ++g) sums[g] += e * c[g];
      }
      std::memcpy(dots + o * kLanes, sums, sizeof sums);
    }
    Lanes rgb[3];
    for (int c = 0; c < 3; ++c) rgb[c] = load_lanes(dots + c * kLanes);
    for (int i = 0; i < n_k; ++i) {
      // Past `count`, the weights' padding or the next vector's: unused lanes.
      const Lanes w = load_lanes(in.weights + i * in.size + j0);
      for (int c = 0; c < 3; ++c) rgb[c] += w * load_lanes(dots + (3 * (i + 1) + c) * kLanes);
    }
    store_packet(rgb, in.vertices + j0, count, red, green, blue);
  }
}

}  // namespace

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
  out.resize(t.vertices(), 3);
  float* red = out.col(0).data();
  float* green = out.col(1).data();
  float* blue = out.col(2).data();
  if (!exit_values) {
    for_each_cluster(l, 0,
                     [&](Eigen::Index k, const float* constants, const std::int32_t* vertices,
                         std::int64_t size, const float* weights, float*) {
                       const int n_k = t.components_of(k);
                       diffuse_kernel(n_k)(constants, weights, size, n_k, vertices, red, green,
                                           blue);
                     });
    return;
  }
  // Glossy, fused (glossy_cluster).
  const Eigen::Index most = t.components + 1;  // stored vectors of the largest cluster
  const Eigen::Index widest = (3 * most + kDotGroup - 1) / kDotGroup * kDotGroup;
  const std::size_t scratch = std::size_t(rows_ * widest + (rows_ + widest) * kLanes);
  for_each_cluster(l, scratch,
                   [&](Eigen::Index k, const float* constants, const std::int32_t* vertices,
                       std::int64_t size, const float* weights, float* buffer) {
                     glossy_cluster({constants, vertices, size, weights, t.components_of(k)}, rows_,
                                    *exit_values, buffer, red, green, blue);
                   });
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
  double weights = t.sparse() ? double(t.weights.size()) : 0.0;
  for (const Part& part : parts_) weights += double(part.weights.size() - kLanes);
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
