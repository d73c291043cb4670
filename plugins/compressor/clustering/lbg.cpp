// LBG / k-means with hyper-box or k-means++ initialisation, null-cluster
// avoidance and Chen's geometry-coherent classification.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "prt/clustering.hpp"
#include "prt/error.hpp"
#include "prt/progress.hpp"
#include "prt/row_blocks.hpp"

namespace prt::clustering {

namespace {

constexpr Eigen::Index kRowBlock = 1024;

// Squared distances of every row to every mean by one float GEMM per row
// block; writes the nearest mean and its distance.
void nearest_means(const MatrixXfRow& x, const RowMatrixXd& means, std::vector<std::int32_t>& label,
                   std::vector<double>& distance) {
  const Eigen::MatrixXf mt = means.transpose().cast<float>();  // n x k
  const Eigen::RowVectorXf mean_norms = mt.colwise().squaredNorm();
  for_each_row_block(Eigen::Index(0), x.rows(), kRowBlock,
                     [&](Eigen::Index begin, Eigen::Index end) {
                       const Eigen::Index rows = end - begin;
                       const Eigen::MatrixXf dots = x.middleRows(begin, rows) * mt;
                       for (Eigen::Index i = 0; i < rows; ++i) {
                         const float row_norm = x.row(begin + i).squaredNorm();
                         Eigen::Index best = 0;
                         const float d = (mean_norms - 2.f * dots.row(i)).minCoeff(&best);
                         label[begin + i] = static_cast<std::int32_t>(best);
                         distance[begin + i] = std::max(0.0, double(d) + row_norm);
                       }
                     });
}

// Chen's E_ij = |x_i - mean_j| + alpha * min_{k in j, k != i} |P_i - P_k|, with
// positions scaled by the bounding-box diagonal so alpha does not depend on
// the model's units. Candidates are visited in increasing signal distance and
// pruned once the signal term alone exceeds the best E.
void nearest_coherent(const MatrixXfRow& x, const RowMatrixXd& means, const Mesh& mesh,
                      double alpha, std::vector<std::int32_t>& label,
                      std::vector<double>& distance) {
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
      });
}

RowMatrixXd hyperbox_init(const MatrixXfRow& x, int k, std::mt19937_64& rng) {
  const Eigen::RowVectorXf lo = x.colwise().minCoeff(), hi = x.colwise().maxCoeff();
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  RowMatrixXd means(k, x.cols());
  for (int j = 0; j < k; ++j)
    for (Eigen::Index d = 0; d < x.cols(); ++d)
      means(j, d) = lo[d] + uniform(rng) * (double(hi[d]) - lo[d]);
  return means;
}

RowMatrixXd kmeans_plus_plus_init(const MatrixXfRow& x, int k, std::mt19937_64& rng) {
  RowMatrixXd means(k, x.cols());
  std::vector<double> d2(x.rows(), std::numeric_limits<double>::infinity());
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  Eigen::Index chosen = std::uniform_int_distribution<Eigen::Index>(0, x.rows() - 1)(rng);
  for (int j = 0; j < k; ++j) {
    means.row(j) = x.row(chosen).cast<double>();
    const Eigen::RowVectorXf c = x.row(chosen);
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, x.rows(), 4096), [&](const auto& r) {
      for (Eigen::Index p = r.begin(); p < r.end(); ++p)
        d2[p] = std::min(d2[p], double((x.row(p) - c).squaredNorm()));
    });
    if (j + 1 == k) break;
    double total = 0;
    for (double d : d2) total += d;
    if (total <= 0) {  // all remaining points coincide with a mean
      chosen = std::uniform_int_distribution<Eigen::Index>(0, x.rows() - 1)(rng);
      continue;
    }
    double target = uniform(rng) * total;
    chosen = x.rows() - 1;
    for (Eigen::Index p = 0; p < x.rows(); ++p)
      if ((target -= d2[p]) <= 0) {
        chosen = p;
        break;
      }
  }
  return means;
}

// Recomputes means; refills each empty cluster by splitting the most
// populous one in two (Chen's null-cluster avoidance): its point farthest from
// the mean and the point farthest from that one seed the halves. Returns the
// number of clusters refilled.
int update_means(const MatrixXfRow& x, std::vector<std::int32_t>& label, std::vector<double>& dist,
                 RowMatrixXd& means) {
  const int k = static_cast<int>(means.rows());
  std::vector<Eigen::Index> count(k, 0);
  RowMatrixXd sums = RowMatrixXd::Zero(k, x.cols());
  // Per cluster on every core, each summing its members in vertex order.
  const auto members = members_of(label, k);
  tbb::parallel_for(0, k, [&](int j) {
    for (std::uint32_t p : members[j]) sums.row(j) += x.row(p).cast<double>();
    count[j] = static_cast<Eigen::Index>(members[j].size());
  });
  int refilled = 0;
  for (int j = 0; j < k; ++j) {
    if (count[j] > 0) continue;
    const int largest =
        static_cast<int>(std::max_element(count.begin(), count.end()) - count.begin());
    if (count[largest] < 2) break;  // fewer points than clusters
    std::vector<Eigen::Index> members;
    for (Eigen::Index p = 0; p < x.rows(); ++p)
      if (label[p] == largest) members.push_back(p);
    const Eigen::RowVectorXd centre = sums.row(largest) / double(count[largest]);
    auto farthest_from = [&](const Eigen::RowVectorXd& point) {
      Eigen::Index best = members[0];
      double best_distance = -1;
      for (Eigen::Index p : members) {
        const double d = (x.row(p).cast<double>() - point).squaredNorm();
        if (d > best_distance) best_distance = d, best = p;
      }
      return best;
    };
    const Eigen::RowVectorXd a = x.row(farthest_from(centre)).cast<double>();
    const Eigen::RowVectorXd b = x.row(farthest_from(a)).cast<double>();
    sums.row(largest).setZero(), sums.row(j).setZero();
    count[largest] = count[j] = 0;
    for (Eigen::Index p : members) {
      const Eigen::RowVectorXd v = x.row(p).cast<double>();
      const double da = (v - a).squaredNorm(), db = (v - b).squaredNorm();
      const int target = db < da ? j : largest;
      label[p] = target;
      dist[p] = std::min(da, db);
      sums.row(target) += v;
      ++count[target];
    }
    if (count[j] == 0) break;  // all points identical: nothing to split
    ++refilled;
  }
  for (int j = 0; j < k; ++j)
    if (count[j] > 0) means.row(j) = sums.row(j) / double(count[j]);
  return refilled;
}

}  // namespace

std::vector<std::vector<std::uint32_t>> members_of(const std::vector<std::int32_t>& labels,
                                                   int clusters) {
  std::vector<std::vector<std::uint32_t>> members(clusters);
  for (std::size_t p = 0; p < labels.size(); ++p)
    members[labels[p]].push_back(static_cast<std::uint32_t>(p));
  return members;
}

Clusters lbg(const MatrixXfRow& x, const LbgOptions& options) {
  if (options.clusters < 1) throw Error("LBG: need at least one cluster");
  if (x.rows() == 0) throw Error("LBG: no data");
  if (options.alpha > 0 && !options.mesh)
    throw Error("LBG: geometry-coherent clustering (alpha > 0) needs the mesh");
  const int k = static_cast<int>(std::min<Eigen::Index>(options.clusters, x.rows()));
  std::mt19937_64 rng(options.seed);
  Clusters result;
  Stopwatch init_clock;
  result.means = options.init == Init::kmeans_plus_plus ? kmeans_plus_plus_init(x, k, rng)
                                                        : hyperbox_init(x, k, rng);
  result.log.push_back({init_clock.seconds(), 0, x.rows(), x.cols(), k, "init"});
  result.labels.assign(x.rows(), 0);
  std::vector<double> distance(x.rows(), 0.0);
  double previous = std::numeric_limits<double>::infinity();
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    Stopwatch clock;
    if (options.alpha > 0 && iteration > 0)
      nearest_coherent(x, result.means, *options.mesh, options.alpha, result.labels, distance);
    else
      nearest_means(x, result.means, result.labels, distance);
    const int refilled = update_means(x, result.labels, distance, result.means);
    double energy = 0;
    for (double d : distance) energy += d;
    result.energy = energy;
    result.iterations = iteration + 1;
    result.log.push_back({clock.seconds(), energy, x.rows(), x.cols(), k, "lbg"});
    if (refilled == 0 && (energy == 0 || (previous - energy) / previous < options.tolerance)) break;
    previous = energy;
  }
  // Energy of the final means (the loop's figure is of the previous ones).
  double energy = 0;
  for (Eigen::Index p = 0; p < x.rows(); ++p)
    energy += (x.row(p).cast<double>() - result.means.row(result.labels[p])).squaredNorm();
  result.energy = energy;
  return result;
}

}  // namespace prt::clustering
