// LBG / k-means with hyper-box or k-means++ initialisation, null-cluster
// avoidance and Chen's geometry-coherent classification. Works on the rows a
// process holds (Rows): classification is local, sums go through segments.
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>

#include "kept_on_ranks.hpp"
#include "prt/clustering.hpp"
#include "prt/error.hpp"
#include "prt/log.hpp"
#include "prt/part_keeper.hpp"
#include "prt/progress.hpp"
#include "prt/row_blocks.hpp"

namespace prt::clustering {

namespace {

constexpr Eigen::Index kRowBlock = 1024;

// Squared distances of every row to every mean by one float GEMM per row
// block; writes the nearest mean and its distance. The search runs down the
// product's columns (contiguous), keeping each row's best so far, so it
// vectorises over rows; a per-row argmin along the strided rows took as long
// as the GEMM. Buffers are kept per thread.
void nearest_means(const Rows& source, const RowMatrixXd& means, std::vector<std::int32_t>& label,
                   std::vector<double>& distance) {
  const auto& x = source.x;
  const Eigen::MatrixXf mt = means.transpose().cast<float>();  // n x k
  const Eigen::RowVectorXf mean_norms = mt.colwise().squaredNorm();
  struct Scratch {
    Eigen::MatrixXf dots;
    std::vector<float> best;
    std::vector<std::int32_t> which;
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  for_each_row_block(
      Eigen::Index(0), x.rows(), kRowBlock, [&](Eigen::Index begin, Eigen::Index end) {
        const Eigen::Index rows = end - begin;
        Scratch& local = scratch.local();
        local.dots.resize(rows, mt.cols());
        local.dots.noalias() = x.middleRows(begin, rows) * mt;
        local.best.resize(std::size_t(rows));
        local.which.assign(std::size_t(rows), 0);
        float* best = local.best.data();
        std::int32_t* which = local.which.data();
        const float* column = local.dots.data();
        for (Eigen::Index i = 0; i < rows; ++i) best[i] = mean_norms[0] - 2.f * column[i];
        // Strictly smaller replaces: the first nearest mean wins ties.
        for (Eigen::Index j = 1; j < mt.cols(); ++j) {
          column = local.dots.col(j).data();
          const float norm = mean_norms[j];
          const std::int32_t index = static_cast<std::int32_t>(j);
          for (Eigen::Index i = 0; i < rows; ++i) {
            const float d = norm - 2.f * column[i];
            const bool closer = d < best[i];
            best[i] = closer ? d : best[i];
            which[i] = closer ? index : which[i];
          }
        }
        for (Eigen::Index i = 0; i < rows; ++i) {
          label[begin + i] = which[i];
          distance[begin + i] =
              std::max(0.0, double(best[i]) + double(x.row(begin + i).squaredNorm()));
        }
        source.release(begin, end);
      });
}

// Chen's E_ij = |x_i - mean_j| + alpha * min_{k in j, k != i} |P_i - P_k|, with
// positions scaled by the bounding-box diagonal so alpha does not depend on
// the model's units. Candidates are visited in increasing signal distance and
// pruned once the signal term alone exceeds the best E.
void nearest_coherent(const Rows& source, const RowMatrixXd& means, const Mesh& mesh, double alpha,
                      std::vector<std::int32_t>& label, std::vector<double>& distance) {
  const auto& x = source.x;
  const auto members = members_of(label, static_cast<int>(means.rows()));
  const float scale = 1.f / std::max(1e-30f, (mesh.bounds_max() - mesh.bounds_min()).norm());
  const Eigen::MatrixXf mt = means.transpose().cast<float>();
  const Eigen::RowVectorXf mean_norms = mt.colwise().squaredNorm();
  const std::vector<std::int32_t> previous = label;
  for_each_row_block(
      Eigen::Index(0), x.rows(), kRowBlock, [&](Eigen::Index begin, Eigen::Index end) {
        const Eigen::Index rows = end - begin;
        const Eigen::MatrixXf dots = x.middleRows(begin, rows) * mt;
        std::vector<std::pair<double, std::int32_t>> order(means.rows());
        for (Eigen::Index i = 0; i < rows; ++i) {
          const Eigen::Index p = begin + i;
          const float row_norm = x.row(p).squaredNorm();
          for (Eigen::Index j = 0; j < means.rows(); ++j)
            order[j] = {
                std::sqrt(std::max(0.0, double(mean_norms[j] - 2.f * dots(i, j) + row_norm))),
                static_cast<std::int32_t>(j)};
          std::sort(order.begin(), order.end());
          double best = std::numeric_limits<double>::infinity();
          std::int32_t best_label = previous[p];
          for (const auto& [signal, j] : order) {
            if (signal >= best) break;
            double geometric = std::numeric_limits<double>::infinity();
            for (std::uint32_t k : members[j])
              if (k != p)
                geometric = std::min(geometric,
                                     double((mesh.positions[k] - mesh.positions[p]).squaredNorm()));
            const double e = signal + alpha * std::sqrt(geometric) * scale;
            if (e < best) best = e, best_label = j;
          }
          label[p] = best_label;
          const double d = (x.row(p).cast<double>() - means.row(best_label)).squaredNorm();
          distance[p] = d;
        }
        source.release(begin, end);
      });
}

RowMatrixXd hyperbox_init(const Rows& rows, int k, std::mt19937_64& rng) {
  const Eigen::Index n = rows.cols();
  Eigen::RowVectorXd lo = Eigen::RowVectorXd::Constant(n, std::numeric_limits<double>::infinity());
  Eigen::RowVectorXd hi = -lo;
  for (Eigen::Index begin = 0; begin < rows.local(); begin += kSegmentRows) {
    const Eigen::Index height = std::min(kSegmentRows, rows.local() - begin);
    lo = lo.cwiseMin(rows.x.middleRows(begin, height).colwise().minCoeff().cast<double>());
    hi = hi.cwiseMax(rows.x.middleRows(begin, height).colwise().maxCoeff().cast<double>());
    rows.release(begin, begin + height);
  }
  rows.parts->min_max(lo, hi);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  RowMatrixXd means(k, n);
  for (int j = 0; j < k; ++j)
    for (Eigen::Index d = 0; d < n; ++d)
      means(j, d) = float(lo[d]) + uniform(rng) * (hi[d] - float(lo[d]));
  return means;
}

// k-means++: each next mean is drawn with probability proportional to the
// squared distance to the nearest chosen one. The draw walks the segments'
// sums, then the rows of the segment it falls in.
RowMatrixXd kmeans_plus_plus_init(const Rows& rows, int k, std::mt19937_64& rng) {
  const Eigen::Index n = rows.cols(), total = rows.total();
  const Eigen::Index segments = (total + kSegmentRows - 1) / kSegmentRows;
  const Eigen::Index first_segment = rows.shard.first / kSegmentRows;
  const auto& x = rows.x;
  RowMatrixXd means(k, n);
  std::vector<double> d2(std::size_t(x.rows()), std::numeric_limits<double>::infinity());
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  Eigen::Index chosen = std::uniform_int_distribution<Eigen::Index>(0, total - 1)(rng);
  for (int j = 0; j < k; ++j) {
    means.row(j) = rows.fetch(chosen);
    const Eigen::RowVectorXf c = means.row(j).cast<float>();
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, x.rows(), 4096), [&](const auto& r) {
      for (Eigen::Index p = r.begin(); p < r.end(); ++p)
        d2[p] = std::min(d2[p], double((x.row(p) - c).squaredNorm()));
      rows.release(r.begin(), r.end());
    });
    if (j + 1 == k) break;
    // Every segment's sum, in segment order, on every rank.
    std::vector<double> mine;
    for (Eigen::Index s = first_segment; s * kSegmentRows < rows.shard.last; ++s) {
      const auto [begin, end] = rows.segment_rows(s);
      double t = 0;
      for (Eigen::Index p = begin; p < end; ++p) t += d2[std::size_t(p)];
      mine.push_back(t);
    }
    std::vector<double> sums;
    for (const auto& part : rows.parts->allgather(mine))
      sums.insert(sums.end(), part.begin(), part.end());
    if (Eigen::Index(sums.size()) != segments)
      throw Error("k-means++: ranks hold a wrong number of segments");
    double all = 0;
    for (double s : sums) all += s;
    if (all <= 0) {  // all remaining points coincide with a mean
      chosen = std::uniform_int_distribution<Eigen::Index>(0, total - 1)(rng);
      continue;
    }
    double target = uniform(rng) * all;
    Eigen::Index segment = segments - 1;
    for (Eigen::Index s = 0; s < segments; ++s) {
      if (target - sums[std::size_t(s)] <= 0) {
        segment = s;
        break;
      }
      target -= sums[std::size_t(s)];
    }
    // The segment's holder walks its rows; the others learn the index.
    const Eigen::Index begin = segment_begin(segment), end = segment_end(segment, total);
    std::int64_t found = -1;
    if (begin >= rows.shard.first && begin < rows.shard.last) {
      found = end - 1;
      for (Eigen::Index p = begin; p < end; ++p)
        if ((target -= d2[std::size_t(p - rows.shard.first)]) <= 0) {
          found = p;
          break;
        }
    }
    chosen = static_cast<Eigen::Index>(rows.parts->argmax(0.0, found).second);
  }
  return means;
}

// The member of cluster `cluster` farthest from `point` (ties: the lowest
// index), over every rank; returns its global index.
Eigen::Index farthest_member(const Rows& rows, const std::vector<std::int32_t>& label, int cluster,
                             const Eigen::RowVectorXd& point) {
  double best_distance = -1;
  std::int64_t best = -1;
  for (Eigen::Index p = 0; p < rows.local(); ++p) {
    if (label[std::size_t(p)] != cluster) continue;
    const double d = (rows.x.row(p).cast<double>() - point).squaredNorm();
    if (d > best_distance) best_distance = d, best = rows.shard.first + p;
  }
  rows.release_all();
  return static_cast<Eigen::Index>(rows.parts->argmax(best_distance, best).second);
}

// Recomputes means; refills each empty cluster by splitting the most
// populous one in two (Chen's null-cluster avoidance): its point farthest from
// the mean and the point farthest from that one seed the halves. Returns the
// number of clusters refilled.
int update_means(const Rows& rows, std::vector<std::int32_t>& label, std::vector<double>& dist,
                 RowMatrixXd& means) {
  const int k = static_cast<int>(means.rows());
  ClusterSums sums = cluster_sums(rows, label, k);
  int refilled = 0;
  for (int j = 0; j < k; ++j) {
    if (sums.counts[std::size_t(j)] > 0) continue;
    const int largest = static_cast<int>(std::max_element(sums.counts.begin(), sums.counts.end()) -
                                         sums.counts.begin());
    if (sums.counts[std::size_t(largest)] < 2) break;  // fewer points than clusters
    const Eigen::RowVectorXd centre = sums.sums.row(largest) / sums.counts[std::size_t(largest)];
    const Eigen::RowVectorXd a = rows.fetch(farthest_member(rows, label, largest, centre));
    const Eigen::RowVectorXd b = rows.fetch(farthest_member(rows, label, largest, a));
    for (Eigen::Index p = 0; p < rows.local(); ++p) {
      if (label[std::size_t(p)] != largest) continue;
      const Eigen::RowVectorXd v = rows.x.row(p).cast<double>();
      const double da = (v - a).squaredNorm(), db = (v - b).squaredNorm();
      label[std::size_t(p)] = db < da ? j : largest;
      dist[std::size_t(p)] = std::min(da, db);
    }
    rows.release_all();
    sums = cluster_sums(rows, label, k);
    if (sums.counts[std::size_t(j)] == 0) break;  // all points identical: nothing to split
    ++refilled;
  }
  for (int j = 0; j < k; ++j)
    if (sums.counts[std::size_t(j)] > 0)
      means.row(j) = sums.sums.row(j) / sums.counts[std::size_t(j)];
  return refilled;
}

// The loop's state between two iterations, kept in a checkpoint: the means
// and the figures in one part ("lbg.state", by rank 0), written after every
// rank's labels (each rank its shard's rows, in one of two parts by the
// parity of a count of saves, each led by its count), so a kill between the
// writes leaves the previous state whole.
struct LbgState {
  int next_iteration = 0;
  int sequence = 0;  // counts the states kept by one run
  double previous = 0, energy = 0;
  RowMatrixXd means;
  std::vector<std::int32_t> labels;  // this rank's rows
};

std::string labels_part(int sequence, const Shard& shard) {
  return "lbg.labels." + std::to_string(sequence % 2) + ".rows-" + std::to_string(shard.first) +
         "-" + std::to_string(shard.last);
}

// Keeps the state; false on every rank when a rank could not write its part.
bool keep_state(const PartKeeper& store, const Rows& rows, const LbgState& s) {
  return keep_on_ranks(
      rows, "LBG",
      [&] {
        std::vector<std::int32_t> labels;
        labels.reserve(s.labels.size() + 1);
        labels.push_back(s.sequence);
        labels.insert(labels.end(), s.labels.begin(), s.labels.end());
        store.save(labels_part(s.sequence, rows.shard), labels);
      },
      [&] {
        // k rows of means, then a row of figures (at least 4 columns wide).
        const Eigen::Index k = s.means.rows(), n = s.means.cols();
        Eigen::MatrixXd state = Eigen::MatrixXd::Zero(k + 1, std::max<Eigen::Index>(n, 4));
        state.topLeftCorner(k, n) = s.means;
        state.row(k).head<4>() << double(s.next_iteration), double(s.sequence), s.previous,
            s.energy;
        store.save("lbg.state", state);
      });
}

// The state a killed run kept, when it fits this run (else none).
std::optional<LbgState> kept_state(const PartKeeper& store, const Rows& rows, int k) {
  const Eigen::Index n = rows.cols();
  if (!store.has("lbg.state")) return std::nullopt;
  const Eigen::MatrixXd state = store.load_doubles("lbg.state");
  if (state.rows() != k + 1 || state.cols() != std::max<Eigen::Index>(n, 4)) return std::nullopt;
  LbgState s;
  s.next_iteration = static_cast<int>(state(k, 0));
  s.sequence = static_cast<int>(state(k, 1));
  s.previous = state(k, 2);
  s.energy = state(k, 3);
  s.means = state.topLeftCorner(k, n);
  const std::string part = labels_part(s.sequence, rows.shard);
  if (!store.has(part)) return std::nullopt;  // another rank count: its shards differ
  std::vector<std::int32_t> labels = store.load_ints(part);
  if (Eigen::Index(labels.size()) != rows.local() + 1 || labels[0] != s.sequence)
    return std::nullopt;
  s.labels.assign(labels.begin() + 1, labels.end());
  for (std::int32_t l : s.labels)
    if (l < 0 || l >= k) return std::nullopt;
  return s;
}

}  // namespace

std::vector<std::vector<std::uint32_t>> members_of(const std::vector<std::int32_t>& labels,
                                                   int clusters) {
  std::vector<std::vector<std::uint32_t>> members(clusters);
  for (std::size_t p = 0; p < labels.size(); ++p)
    if (labels[p] >= 0) members[labels[p]].push_back(static_cast<std::uint32_t>(p));
  return members;
}

Clusters lbg(const Rows& rows, const LbgOptions& options) {
  if (options.clusters < 1) throw Error("LBG: need at least one cluster");
  if (rows.total() == 0) throw Error("LBG: no data");
  if (options.alpha > 0 && !options.mesh)
    throw Error("LBG: geometry-coherent clustering (alpha > 0) needs the mesh");
  if (options.alpha > 0 && rows.distributed())
    throw Error("LBG: geometry-coherent clustering (alpha > 0) needs every vertex in one process");
  const int k = static_cast<int>(std::min<Eigen::Index>(options.clusters, rows.total()));
  std::mt19937_64 rng(options.seed);
  Clusters result;
  double previous = std::numeric_limits<double>::infinity();
  int first_iteration = 0;
  std::optional<LbgState> kept;
  try {
    if (options.keep) kept = kept_state(*options.keep, rows, k);
  } catch (const Error& e) {  // a damaged part: start afresh rather than fail every rerun
    log_warning(std::string("LBG: the kept state is unreadable, starting afresh: ") + e.what());
  }
  if (options.keep && rows.any(!kept)) kept.reset();  // every rank resumes, or none
  const PartKeeper* keep = options.keep;  // null once keeping failed, on every rank alike
  int sequence = kept ? kept->sequence + 1 : 0;
  if (kept) {
    if (rows.parts->first())
      log_info("resuming: LBG at iteration " + std::to_string(kept->next_iteration + 1) +
               ", kept in " + options.keep->where());
    result.means = std::move(kept->means);
    result.labels = std::move(kept->labels);
    previous = kept->previous;
    result.energy = kept->energy;
    result.iterations = first_iteration = kept->next_iteration;
  } else {
    Stopwatch init_clock;
    result.means = options.init == Init::kmeans_plus_plus ? kmeans_plus_plus_init(rows, k, rng)
                                                          : hyperbox_init(rows, k, rng);
    result.log.push_back({init_clock.seconds(), 0, rows.total(), rows.cols(), k, "init"});
    result.labels.assign(std::size_t(rows.local()), 0);
  }
  std::vector<double> distance(std::size_t(rows.local()), 0.0);
  Stopwatch since_kept;
  for (int iteration = first_iteration; iteration < options.max_iterations; ++iteration) {
    Progress::check_interrupt();
    Stopwatch clock;
    if (options.alpha > 0 && iteration > 0)
      nearest_coherent(rows, result.means, *options.mesh, options.alpha, result.labels, distance);
    else
      nearest_means(rows, result.means, result.labels, distance);
    const int refilled = update_means(rows, result.labels, distance, result.means);
    const double energy = rows.sum(distance);
    result.energy = energy;
    result.iterations = iteration + 1;
    result.log.push_back({clock.seconds(), energy, rows.total(), rows.cols(), k, "lbg"});
    if (refilled == 0 && (energy == 0 || (previous - energy) / previous < options.tolerance)) break;
    previous = energy;
    // Rank 0's clock decides for every rank, so that all keep the same iteration.
    if (keep && rows.any(rows.parts->first() && since_kept.seconds() >= options.keep_seconds)) {
      if (!keep_state(*keep, rows,
                      {iteration + 1, sequence++, previous, energy, result.means, result.labels}))
        keep = nullptr;
      since_kept = Stopwatch();
    }
  }
  // Energy of the final means (the loop's figure is of the previous ones).
  for_each_row_block(
      Eigen::Index(0), rows.local(), kRowBlock, [&](Eigen::Index begin, Eigen::Index end) {
        for (Eigen::Index p = begin; p < end; ++p)
          distance[std::size_t(p)] =
              (rows.x.row(p).cast<double>() - result.means.row(result.labels[std::size_t(p)]))
                  .squaredNorm();
        rows.release(begin, end);
      });
  result.energy = rows.sum(distance);
  return result;
}

}  // namespace prt::clustering
