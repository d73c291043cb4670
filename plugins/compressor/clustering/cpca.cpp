// Clustered PCA: static (VQ then PCA, §4.1), iterative (classification by
// approximation error, components added one at a time, §4.2) and adaptive
// (per-cluster component counts by D_i^2 / m_k under a total budget, §4.3).
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <optional>

#include "prt/clustering.hpp"
#include "prt/error.hpp"
#include "prt/progress.hpp"
#include "prt/row_blocks.hpp"

namespace prt::clustering {

namespace {

std::vector<ClusterModel> fit_all(const Rows& rows, const std::vector<std::int32_t>& labels,
                                  int clusters, const std::vector<int>& components,
                                  std::vector<double>* counts = nullptr) {
  return fit_models(rows, labels, clusters, components, counts);
}

// Assigns every row to the cluster of least approximation error:
// |x - m_j|^2 - sum_i ((x - m_j) . u_ji)^2, from two float GEMMs per row block.
// Returns the total error and fills each row's error.
double classify(const Rows& rows, const std::vector<ClusterModel>& models,
                std::vector<std::int32_t>& labels, std::vector<double>& errors) {
  const MatrixXfRow& x = rows.x;
  const int k = static_cast<int>(models.size());
  const Eigen::Index n = x.cols();
  std::vector<Eigen::Index> offset(k + 1, 0);
  for (int j = 0; j < k; ++j) offset[j + 1] = offset[j] + models[j].basis.rows();
  Eigen::MatrixXf means_t(n, k), basis_t(n, offset[k]);
  Eigen::RowVectorXf mean_norms(k);
  Eigen::RowVectorXf mean_projections(offset[k]);
  for (int j = 0; j < k; ++j) {
    means_t.col(j) = models[j].mean.transpose().cast<float>();
    mean_norms[j] = static_cast<float>(models[j].mean.squaredNorm());
    for (Eigen::Index i = 0; i < models[j].basis.rows(); ++i) {
      basis_t.col(offset[j] + i) = models[j].basis.row(i).transpose().cast<float>();
      mean_projections[offset[j] + i] =
          static_cast<float>(models[j].basis.row(i).dot(models[j].mean));
    }
  }
  for_each_row_block(Eigen::Index(0), x.rows(), Eigen::Index(512),
                     [&](Eigen::Index begin, Eigen::Index end) {
                       const Eigen::Index height = end - begin;
                       const auto block = x.middleRows(begin, height);
                       const Eigen::MatrixXf dots = block * means_t;
                       Eigen::MatrixXf projections = block * basis_t;
                       projections.rowwise() -= mean_projections;
                       for (Eigen::Index i = 0; i < height; ++i) {
                         const float row_norm = block.row(i).squaredNorm();
                         float best = std::numeric_limits<float>::infinity();
                         int best_label = 0;
                         for (int j = 0; j < k; ++j) {
                           float e = row_norm - 2.f * dots(i, j) + mean_norms[j];
                           const Eigen::Index count = offset[j + 1] - offset[j];
                           if (count)
                             e -= projections.row(i).segment(offset[j], count).squaredNorm();
                           if (e < best) best = e, best_label = j;
                         }
                         labels[begin + i] = best_label;
                       }
                     });
  // Errors in double on every core; their sum through segments (the same
  // figure whatever the number of cores or ranks).
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, x.rows(), 1024), [&](const auto& r) {
    for (Eigen::Index p = r.begin(); p < r.end(); ++p)
      errors[p] = approximation_error(x, p, models[labels[p]]);
  });
  return rows.sum(errors);
}

// Gives each empty cluster the worst-approximated point of the most populous
// cluster (ties: the lowest index, over every rank). Returns true when
// something moved.
bool refill_empty(const Rows& rows, std::vector<std::int32_t>& labels, std::vector<double>& errors,
                  int clusters) {
  std::vector<double> count = cluster_sums(rows, labels, clusters).counts;
  bool moved = false;
  for (int j = 0; j < clusters; ++j) {
    if (count[j] > 0) continue;
    const int largest =
        static_cast<int>(std::max_element(count.begin(), count.end()) - count.begin());
    if (count[largest] < 2) break;
    double worst_error = -1;
    std::int64_t worst = -1;
    for (std::size_t p = 0; p < labels.size(); ++p)
      if (labels[p] == largest && errors[p] > worst_error)
        worst_error = errors[p], worst = rows.shard.first + std::int64_t(p);
    worst = allreduce_argmax(rows.comm, worst_error, worst).second;
    if (worst >= rows.shard.first && worst < rows.shard.last) {
      labels[std::size_t(worst - rows.shard.first)] = j;
      errors[std::size_t(worst - rows.shard.first)] = 0;
    }
    --count[largest];
    count[j] = 1;
    moved = true;
  }
  return moved;
}

IterationLog gemm_log(const Rows& rows, const std::vector<ClusterModel>& models, double seconds,
                      double energy, const std::string& stage) {
  Eigen::Index cols = 0;
  for (const auto& m : models) cols += 1 + m.basis.rows();
  return {seconds, energy, rows.local(), rows.cols(), cols, stage};
}

// Adaptive allocation: candidate vector i of cluster k reduces the squared
// error by D_i^2 and costs m_k weights plus its own n floats (the storage
// formula), so taking them in decreasing D_i^2 / (m_k + n) while the total
// stays within `budget` compares at exactly the storage of fixed n'. (Sloan
// ranks by D_i^2 / m_k and counts weights only; the representative's n floats
// make the comparison exact.)
std::vector<int> allocate(const std::vector<ClusterModel>& models,
                          const std::vector<double>& members, double budget,
                          Eigen::Index dimension) {
  struct Candidate {
    double rate;
    int cluster, index;
  };
  std::vector<Candidate> candidates;
  for (std::size_t k = 0; k < models.size(); ++k) {
    const double cost = members[k] + double(dimension);
    if (members[k] == 0) continue;
    for (Eigen::Index i = 0; i < models[k].eigenvalues.size(); ++i)
      if (models[k].eigenvalues[i] > 0)
        candidates.push_back({models[k].eigenvalues[i] / cost, int(k), int(i)});
  }
  std::sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) {
    return a.rate != b.rate         ? a.rate > b.rate
           : a.cluster != b.cluster ? a.cluster < b.cluster
                                    : a.index < b.index;
  });
  std::vector<int> count(models.size(), 0);
  double spent = 0;
  for (const auto& c : candidates) {
    const double cost = members[c.cluster] + double(dimension);
    if (c.index != count[c.cluster] || spent + cost > budget) continue;  // in order, within budget
    ++count[c.cluster];
    spent += cost;
  }
  return count;
}

void truncate(std::vector<ClusterModel>& models, const std::vector<int>& count) {
  for (std::size_t k = 0; k < models.size(); ++k) {
    models[k].basis.conservativeResize(count[k], Eigen::NoChange);
    models[k].eigenvalues.conservativeResize(count[k]);
  }
}

}  // namespace

CpcaResult cpca(const Rows& rows, const CpcaOptions& options) {
  if (options.components < 0) throw Error("CPCA: negative component count");
  CpcaResult result;
  Clusters vq = lbg(rows, options.lbg);
  result.log = vq.log;
  result.labels = std::move(vq.labels);
  const int k = static_cast<int>(vq.means.rows());
  const int n_prime = static_cast<int>(std::min<Eigen::Index>(options.components, rows.cols()));
  std::vector<double> errors(std::size_t(rows.local()), 0.0);

  std::optional<Progress> progress;
  if (options.method != Method::static_pca) {
    const int passes = n_prime * options.iterations_per_component +
                       (options.method == Method::adaptive ? options.adaptive_iterations : 0);
    progress.emplace(options.method == Method::adaptive ? "adaptive CPCA" : "iterative CPCA",
                     passes, "passes");
    // Components one at a time; classification by approximation error.
    for (int c = 1; c <= n_prime; ++c) {
      for (int iteration = 0; iteration < options.iterations_per_component; ++iteration) {
        Progress::check_interrupt();
        Stopwatch clock;
        const auto models = fit_all(rows, result.labels, k, std::vector<int>(k, c));
        const std::vector<std::int32_t> before = result.labels;
        const double energy = classify(rows, models, result.labels, errors);
        const bool refilled = refill_empty(rows, result.labels, errors, k);
        result.log.push_back(gemm_log(rows, models, clock.seconds(), energy, "iterative"));
        progress->add(1, 1);
        if (!refilled && !rows.any(before != result.labels)) {  // LBG: no point switched
          progress->add(options.iterations_per_component - iteration - 1, 0);
          break;
        }
      }
    }
  }
  std::vector<int> count(k, n_prime);
  if (options.method == Method::adaptive) {
    const int widest = static_cast<int>(std::min<Eigen::Index>(rows.cols(), 2 * n_prime + 8));
    // Storage of fixed n' beyond the means: v n' weights + k n' n representatives.
    const double budget = double(rows.total()) * n_prime + double(k) * n_prime * rows.cols();
    std::vector<double> sizes;
    for (int iteration = 0; iteration < options.adaptive_iterations; ++iteration) {
      Progress::check_interrupt();
      Stopwatch clock;
      auto models = fit_all(rows, result.labels, k, std::vector<int>(k, widest), &sizes);
      count = allocate(models, sizes, budget, rows.cols());
      truncate(models, count);
      const double energy = classify(rows, models, result.labels, errors);
      refill_empty(rows, result.labels, errors, k);
      result.log.push_back(gemm_log(rows, models, clock.seconds(), energy, "adaptive"));
      progress->add(1, 1);
    }
    // Final representatives for the final classification, same allocation.
    auto models = fit_all(rows, result.labels, k, std::vector<int>(k, widest), &sizes);
    count = allocate(models, sizes, budget, rows.cols());
    truncate(models, count);
    result.models = std::move(models);
    return result;
  }
  result.models = fit_all(rows, result.labels, k, count);
  return result;
}

}  // namespace prt::clustering
