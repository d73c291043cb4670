#include "classify_kernel.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <string>
#include <utility>

#include "first_minimum.hpp"
#include "prt/error.hpp"

namespace prt::clustering {

namespace {

typedef float Lanes __attribute__((vector_size(64)));
static_assert(sizeof(Lanes) == kClassifyLanes * sizeof(float));

// A tile is kRows rows by up to kTypes of a group's panel columns: 24
// accumulators, each register's panel values used by four rows.
constexpr int kRows = 4;
constexpr int kTypes = 6;

Lanes load(const float* p) {
  Lanes v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

void store(float* p, const Lanes& v) {
  std::memcpy(p, &v, sizeof v);
}

// The dots of R rows with types [first, first + C) of one group (`panel` and
// `offset` point at type `first`), folded into each row's base
// (|x|^2 - 2 x . m + |m|^2, when the mean is among them) and sum of squared
// projections. Unrolled for registers: R x C accumulators.
template <int R, int C>
void tile(const float* const* rows, Eigen::Index n, const float* panel, int types,
          const float* offset, bool mean, const float* row_norms, const float* mean_norms,
          Lanes* base, Lanes* sum) {
  Lanes dot[R][C] = {};
  const std::size_t stride = std::size_t(types) * kClassifyLanes;
  for (Eigen::Index i = 0; i < n; ++i) {
    const float* p = panel + std::size_t(i) * stride;
    Lanes column[C];
    for (int c = 0; c < C; ++c) {
      column[c] = load(p + c * kClassifyLanes);
      // In a register, read once for all R rows: folded into each
      // multiply-add as a memory operand, the loads outnumbered the FMAs.
#ifdef __AVX512F__
      asm("" : "+v"(column[c]));
#endif
    }
    for (int r = 0; r < R; ++r) {
      const float value = rows[r][i];
      for (int c = 0; c < C; ++c) dot[r][c] += value * column[c];
    }
  }
  int c = 0;
  if (mean) {
    const Lanes norms = load(mean_norms);
    for (int r = 0; r < R; ++r) base[r] = row_norms[r] - 2.f * dot[r][0] + norms;
    c = 1;
  }
  for (; c < C; ++c) {
    const Lanes projection_of_mean = load(offset + c * kClassifyLanes);
    for (int r = 0; r < R; ++r) {
      const Lanes d = dot[r][c] - projection_of_mean;
      sum[r] += d * d;
    }
  }
}

using Tile = void (*)(const float* const*, Eigen::Index, const float*, int, const float*, bool,
                      const float*, const float*, Lanes*, Lanes*);

template <int R, int... C>
constexpr std::array<Tile, sizeof...(C)> tiles_of_rows(std::integer_sequence<int, C...>) {
  return {&tile<R, C + 1>...};
}

template <int... R>
constexpr std::array<std::array<Tile, kTypes>, sizeof...(R)> tiles(
    std::integer_sequence<int, R...>) {
  return {tiles_of_rows<R + 1>(std::make_integer_sequence<int, kTypes>())...};
}

// tile<R, C> for R in 1..kRows, C in 1..kTypes.
constexpr auto kTiles = tiles(std::make_integer_sequence<int, kRows>());

}  // namespace

PackedClassifier pack_classifier(const std::vector<ClusterModel>& models, int components) {
  PackedClassifier c;
  c.clusters = static_cast<int>(models.size());
  c.dimension = models.empty() ? 0 : models.front().mean.size();
  c.groups = (c.clusters + kClassifyLanes - 1) / kClassifyLanes;
  // Per group, the mean and its clusters' components up to the widest of
  // them (adaptive CPCA gives clusters uneven counts: one cluster of 24
  // directions must not make every group 25 types wide).
  const auto used = [&](std::size_t j) {
    return int(std::min<Eigen::Index>(components, models[j].basis.rows()));
  };
  c.types.assign(std::size_t(c.groups), 1);
  for (std::size_t j = 0; j < models.size(); ++j)
    c.types[j / kClassifyLanes] = std::max(c.types[j / kClassifyLanes], 1 + used(j));
  const std::size_t n = std::size_t(c.dimension);
  c.panel_start.assign(std::size_t(c.groups) + 1, 0);
  for (std::size_t g = 0; g < std::size_t(c.groups); ++g)
    c.panel_start[g + 1] = c.panel_start[g] + std::size_t(c.types[g]) * kClassifyLanes;
  c.panels.assign(c.panel_start.back() * n, 0.f);
  c.offsets.assign(c.panel_start.back(), 0.f);
  c.mean_norms.assign(std::size_t(c.groups) * kClassifyLanes, 0.f);
  for (std::size_t j = 0; j < models.size(); ++j) {
    const ClusterModel& m = models[j];
    const std::size_t g = j / kClassifyLanes, lane = j % kClassifyLanes;
    const std::size_t types = std::size_t(c.types[g]);
    const auto at = [&](std::size_t i, std::size_t type) {
      return c.panel_start[g] * n + (i * types + type) * kClassifyLanes + lane;
    };
    for (std::size_t i = 0; i < n; ++i) c.panels[at(i, 0)] = float(m.mean[Eigen::Index(i)]);
    for (std::size_t t = 0; t < std::size_t(used(j)); ++t) {
      for (std::size_t i = 0; i < n; ++i)
        c.panels[at(i, t + 1)] = float(m.basis(Eigen::Index(t), Eigen::Index(i)));
      c.offsets[c.panel_start[g] + (t + 1) * kClassifyLanes + lane] =
          float(m.basis.row(Eigen::Index(t)).dot(m.mean));
    }
    c.mean_norms[j] = float(m.mean.squaredNorm());
  }
  return c;
}

Eigen::Index classify_block_rows(Eigen::Index dimension) {
  // 109 rows of 600 values left a one-row tile in every block.
  const Eigen::Index rows = 65536 / std::max<Eigen::Index>(1, dimension) / kRows * kRows;
  return std::clamp<Eigen::Index>(rows, 4 * kRows, 256);
}

namespace {

// Every packed cluster's error for rows [begin, end): errors[row width +
// packed cluster], width (returned) the packed clusters padded to groups.
std::size_t packed_errors(RowsRef x, Eigen::Index begin, Eigen::Index end,
                          const PackedClassifier& c, std::vector<float>& errors) {
  const Eigen::Index n = c.dimension, height = end - begin;
  if (x.cols() != n)
    throw Error("clustering: rows of " + std::to_string(x.cols()) +
                " values classified against models of " + std::to_string(n));
  const std::size_t width = std::size_t(c.groups) * kClassifyLanes;
  errors.resize(std::size_t(height) * width + std::size_t(height));
  float* row_norms = errors.data() + std::size_t(height) * width;
  for (Eigen::Index r = 0; r < height; ++r) row_norms[r] = x.row(begin + r).squaredNorm();
  for (int g = 0; g < c.groups; ++g) {
    const int types = c.types[std::size_t(g)];
    const float* panel = c.panels.data() + c.panel_start[std::size_t(g)] * std::size_t(n);
    const float* offsets = c.offsets.data() + c.panel_start[std::size_t(g)];
    const float* mean_norms = c.mean_norms.data() + std::size_t(g) * kClassifyLanes;
    // The types in passes of at most kTypes, as even as they go.
    const int passes = (types + kTypes - 1) / kTypes;
    for (Eigen::Index r0 = 0; r0 < height; r0 += kRows) {
      const int rows = int(std::min<Eigen::Index>(kRows, height - r0));
      const float* row[kRows];
      for (int r = 0; r < rows; ++r) row[r] = x.row(begin + r0 + r).data();
      Lanes base[kRows] = {}, sum[kRows] = {};
      for (int pass = 0, first = 0; pass < passes; ++pass) {
        const int count = types / passes + (pass < types % passes ? 1 : 0);
        kTiles[std::size_t(rows - 1)][std::size_t(count - 1)](
            row, n, panel + std::size_t(first) * kClassifyLanes, types,
            offsets + std::size_t(first) * kClassifyLanes, first == 0, row_norms + r0, mean_norms,
            base, sum);
        first += count;
      }
      for (int r = 0; r < rows; ++r)
        store(&errors[std::size_t(r0 + r) * width + std::size_t(g) * kClassifyLanes],
              base[r] - sum[r]);
    }
  }
  return width;
}

}  // namespace

void classify_rows(RowsRef x, Eigen::Index begin, Eigen::Index end, const PackedClassifier& c,
                   std::int32_t* labels, std::vector<float>& errors) {
  const std::size_t width = packed_errors(x, begin, end, c, errors);
  for (Eigen::Index r = 0; r < end - begin; ++r)
    labels[r] = first_minimum(&errors[std::size_t(r) * width], c.clusters);
}

void classify_rows_kept(RowsRef x, Eigen::Index begin, Eigen::Index end, const PackedClassifier& c,
                        const std::vector<int>& clusters, float* kept, int all,
                        std::int32_t* labels, std::vector<float>& errors) {
  if (clusters.size() != std::size_t(c.clusters))
    throw Error("clustering: " + std::to_string(clusters.size()) + " cluster indices for " +
                std::to_string(c.clusters) + " packed clusters");
  const std::size_t width = c.clusters > 0 ? packed_errors(x, begin, end, c, errors) : 0;
  for (Eigen::Index r = 0; r < end - begin; ++r) {
    float* row = kept + std::size_t(r) * std::size_t(all);
    for (std::size_t j = 0; j < clusters.size(); ++j)
      row[clusters[j]] = errors[std::size_t(r) * width + j];
    labels[r] = first_minimum(row, all);
  }
}

}  // namespace prt::clustering
