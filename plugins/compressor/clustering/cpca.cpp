// Clustered PCA: static (VQ then PCA, §4.1), iterative (classification by
// approximation error, components added one at a time, §4.2) and adaptive
// (per-cluster component counts by D_i^2 / m_k under a total budget, §4.3).
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <numeric>
#include <optional>

#include "classify_kernel.hpp"
#include "cpca_state.hpp"
#include "prt/clustering.hpp"
#include "prt/error.hpp"
#include "prt/log.hpp"
#include "prt/progress.hpp"
#include "prt/row_blocks.hpp"

namespace prt::clustering {

namespace {

// Every row's float error under every cluster, kept from one iteration to
// the next of one component count: a cluster whose model has the same bits
// (the refit keeps the models of clusters whose members did not change:
// 0.82 of the glossy bunny's classification groups are refit over its 80
// iterations) keeps its errors, and only the others are computed.
class KeptErrors {
 public:
  // Rows x clusters floats at most (the bunny's 600-dim rows: 39 MB for 256).
  static constexpr double kMaxBytes = 512e6;

  // The clusters whose errors must be computed for `models` (all of them
  // when nothing is kept, or the component count changed); their models
  // are then the kept ones.
  std::vector<int> stale(const std::vector<ClusterModel>& models, int components,
                         Eigen::Index rows) {
    std::vector<int> out;
    const bool usable = double(rows) * double(models.size()) * sizeof(float) <= kMaxBytes;
    const bool fresh = !usable || components != components_ || models.size() != models_.size();
    if (usable && fresh) errors.assign(std::size_t(rows) * models.size(), 0.f);
    if (!usable) errors.clear();
    for (std::size_t j = 0; j < models.size(); ++j)
      if (fresh || !same_model(models[j], models_[j], components)) out.push_back(int(j));
    components_ = usable ? components : -1;
    models_ = usable ? models : std::vector<ClusterModel>();
    return out;
  }
  bool usable() const { return components_ >= 0; }
  std::vector<float> errors;  // rows x clusters

 private:
  // The same bits in what the classifier packs: the mean and the first
  // `components` directions.
  static bool same_model(const ClusterModel& a, const ClusterModel& b, int components) {
    const auto used = [&](const ClusterModel& m) {
      return std::min<Eigen::Index>(components, m.basis.rows());
    };
    const auto same = [](const double* p, const double* q, Eigen::Index count) {
      return count == 0 || std::memcmp(p, q, std::size_t(count) * sizeof(double)) == 0;
    };
    if (a.mean.size() != b.mean.size() || used(a) != used(b) || a.basis.cols() != b.basis.cols())
      return false;
    return same(a.mean.data(), b.mean.data(), a.mean.size()) &&
           same(a.basis.data(), b.basis.data(), used(a) * a.basis.cols());
  }
  int components_ = -1;
  std::vector<ClusterModel> models_;
};

// Assigns every row to the cluster of least approximation error under the
// first `components` directions of each model:
// |x - m_j|^2 - sum_i ((x - m_j) . u_ji)^2 in float (classify_kernel.hpp).
// Returns the total error and fills each row's error, in double. With
// `kept`, only the clusters whose models changed are classified afresh.
double classify(const Rows& rows, const std::vector<ClusterModel>& models, int components,
                std::vector<std::int32_t>& labels, std::vector<double>& errors,
                KeptErrors* kept = nullptr) {
  const auto& x = rows.x;
  std::vector<int> stale;
  if (kept) stale = kept->stale(models, components, x.rows());
  const bool reuse = kept && kept->usable();
  std::vector<ClusterModel> packed_models;
  if (reuse)
    for (int j : stale) packed_models.push_back(models[std::size_t(j)]);
  const PackedClassifier c = pack_classifier(reuse ? packed_models : models, components);
  // Per thread: each block's errors per row and cluster, kept across blocks.
  tbb::enumerable_thread_specific<std::vector<float>> scratch;
  const Eigen::Index block = classify_block_rows(x.cols());
  const int k = int(models.size());
  for_each_row_block(Eigen::Index(0), x.rows(), block, [&](Eigen::Index begin, Eigen::Index end) {
    if (reuse)
      classify_rows_kept(x, begin, end, c, stale, kept->errors.data() + std::size_t(begin) * k, k,
                         labels.data() + begin, scratch.local());
    else
      classify_rows(x, begin, end, c, labels.data() + begin, scratch.local());
    rows.release(begin, end);
  });
  // Errors in double on every core; their sum through segments (the same
  // figure whatever the number of cores or ranks).
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, x.rows(), 1024), [&](const auto& r) {
    ErrorScratch scratch;
    for (Eigen::Index p = r.begin(); p < r.end(); ++p)
      errors[std::size_t(p)] = approximation_error(
          x, p, models[std::size_t(labels[std::size_t(p)])], components, scratch);
    rows.release(r.begin(), r.end());
  });
  return rows.sum(errors);
}

// Gives each empty cluster the worst-approximated point of the most populous
// cluster (ties: the lowest index, over every rank). Returns true when
// something moved.
bool refill_empty(const Rows& rows, std::vector<std::int32_t>& labels, std::vector<double>& errors,
                  int clusters) {
  std::vector<double> count = cluster_counts(rows, labels, clusters);
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
    worst = rows.parts->argmax(worst_error, worst).second;
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

IterationLog gemm_log(const Rows& rows, const std::vector<ClusterModel>& models, int components,
                      double seconds, double energy, const std::string& stage) {
  Eigen::Index cols = 0;
  for (const auto& m : models) cols += 1 + std::min<Eigen::Index>(m.basis.rows(), components);
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

// Keeps at most count[k] directions of each model.
void truncate(std::vector<ClusterModel>& models, const std::vector<int>& count) {
  for (std::size_t k = 0; k < models.size(); ++k) {
    const Eigen::Index keep = std::min<Eigen::Index>(count[k], models[k].basis.rows());
    models[k].basis.conservativeResize(keep, Eigen::NoChange);
    models[k].eigenvalues.conservativeResize(keep);
  }
}

std::vector<ClusterModel> truncated(std::vector<ClusterModel> models,
                                    const std::vector<int>& count) {
  truncate(models, count);
  return models;
}

// Refits the cluster models for a new labelling, keeping the models of the
// clusters whose members did not change. Each fit computes one direction more
// than asked (when there is room), so that moving to the next component count
// refits only the clusters that changed.
class Refitter {
 public:
  Refitter(const Rows& rows, int clusters) : rows_(rows), k_(clusters) {}

  const std::vector<ClusterModel>& fit(const std::vector<std::int32_t>& labels, int components,
                                       std::vector<double>* counts = nullptr) {
    const int spare = static_cast<int>(std::min<Eigen::Index>(components + 1, rows_.cols()));
    const bool reusable = !models_.empty();
    FitReuse reuse{&models_, {}, components};
    if (reusable) reuse.changed = changed_clusters(rows_, labels_, labels, k_);
    models_ = fit_models(rows_, labels, k_, std::vector<int>(std::size_t(k_), spare), counts,
                         reusable ? &reuse : nullptr);
    labels_ = labels;
    return models_;
  }

  // What a kept state needs, and its restoration.
  const std::vector<ClusterModel>& models() const { return models_; }
  const std::vector<std::int32_t>& labels() const { return labels_; }
  void restore(std::vector<ClusterModel> models, std::vector<std::int32_t> labels) {
    models_ = std::move(models);
    labels_ = std::move(labels);
  }

 private:
  const Rows& rows_;
  int k_;
  std::vector<ClusterModel> models_;
  std::vector<std::int32_t> labels_;
};

// One CPCA encode (Sloan et al. 2003, section 4): LBG clusters, then passes
// that refit each cluster's PCA and reclassify every point by the error of
// its approximation, one component at a time (iterative), then with a
// per-cluster component count from a storage budget (adaptive). The state at
// the start of a pass is kept (options.lbg.keep) so a killed encode resumes.
class CpcaRun {
 public:
  CpcaRun(const Rows& rows, const CpcaOptions& options)
      : rows_(rows),
        options_(options),
        n_prime_(static_cast<int>(std::min<Eigen::Index>(options.components, rows.cols()))),
        k_(static_cast<int>(std::min<Eigen::Index>(options.lbg.clusters, rows.total()))),
        keep_(options.method != Method::static_pca ? options.lbg.keep : nullptr),
        refitter_(rows, k_),
        errors_(std::size_t(rows.local()), 0.0) {}

  CpcaResult run() {
    resume_or_cluster();
    since_kept_ = Stopwatch();  // the first state is kept keep_seconds after LBG
    if (options_.method != Method::static_pca) iterative_passes();
    if (options_.method == Method::adaptive) return adaptive_passes();
    result_.models =
        truncated(refitter_.fit(result_.labels, n_prime_), std::vector<int>(k_, n_prime_));
    return std::move(result_);
  }

 private:
  // A state kept by a killed run of the same encode replaces LBG and the
  // passes it did.
  void resume_or_cluster() {
    std::optional<CpcaState> kept;
    try {
      if (keep_) kept = kept_cpca_state(*keep_, rows_, k_);
    } catch (const Error& e) {  // a damaged part: start afresh rather than fail every rerun
      log_warning(std::string("CPCA: the kept state is unreadable, starting afresh: ") + e.what());
    }
    if (keep_ && rows_.any(!kept)) kept.reset();  // every rank resumes, or none
    if (!kept) {
      Clusters vq = lbg(rows_, options_.lbg);
      result_.log = vq.log;
      result_.labels = std::move(vq.labels);
      return;
    }
    resumed_ = true;
    adaptive_kept_ = kept->phase == 1;
    if (rows_.parts->first())
      log_info("resuming: CPCA at " +
               (adaptive_kept_ ? "adaptive pass " + std::to_string(kept->iteration + 1)
                               : "component " + std::to_string(kept->component) + ", pass " +
                                     std::to_string(kept->iteration + 1)) +
               ", kept in " + keep_->where());
    result_.labels = std::move(kept->labels);
    refitter_.restore(std::move(kept->models), std::move(kept->fitted_labels));
    first_component_ = kept->component;
    first_iteration_ = kept->iteration;
    sequence_ = kept->sequence + 1;
  }

  // Keeps the state at the start of a pass (once a fit has been made), at
  // most every keep_seconds; rank 0's clock decides for every rank, so that
  // all keep the same pass.
  void keep_before_pass(int phase, int component, int iteration) {
    if (!keep_ || refitter_.models().empty() ||
        !rows_.any(rows_.parts->first() && since_kept_.seconds() >= options_.lbg.keep_seconds))
      return;
    if (!keep_cpca_state(*keep_, rows_,
                         {phase, component, iteration, sequence_++, result_.labels,
                          refitter_.labels(), refitter_.models()}))
      keep_ = nullptr;
    since_kept_ = Stopwatch();
  }

  // Components one at a time; classification by approximation error.
  void iterative_passes() {
    const int per_component = options_.iterations_per_component;
    const int passes = n_prime_ * per_component +
                       (options_.method == Method::adaptive ? options_.adaptive_iterations : 0);
    progress_.emplace(options_.method == Method::adaptive ? "adaptive CPCA" : "iterative CPCA",
                      passes, "passes");
    if (resumed_)
      progress_->add(adaptive_kept_ ? n_prime_ * per_component + first_iteration_
                                    : (first_component_ - 1) * per_component + first_iteration_,
                     0);
    KeptErrors kept_errors;
    for (int c = adaptive_kept_ ? n_prime_ + 1 : first_component_; c <= n_prime_; ++c) {
      for (int iteration = c == first_component_ ? first_iteration_ : 0; iteration < per_component;
           ++iteration) {
        Progress::check_interrupt();
        keep_before_pass(0, c, iteration);
        Stopwatch clock;
        const auto& models = refitter_.fit(result_.labels, c);
        const std::vector<std::int32_t> before = result_.labels;
        const double energy = classify(rows_, models, c, result_.labels, errors_, &kept_errors);
        const bool refilled = refill_empty(rows_, result_.labels, errors_, k_);
        result_.log.push_back(gemm_log(rows_, models, c, clock.seconds(), energy, "iterative"));
        progress_->add(1, 1);
        if (!refilled && !rows_.any(before != result_.labels)) {  // LBG: no point switched
          progress_->add(per_component - iteration - 1, 0);
          break;
        }
      }
    }
  }

  // Components per cluster from the budget of fixed n' (v n' weights + k n' n
  // representatives beyond the means), refit and reclassified each pass.
  CpcaResult adaptive_passes() {
    const int widest = static_cast<int>(std::min<Eigen::Index>(rows_.cols(), 2 * n_prime_ + 8));
    const double budget = double(rows_.total()) * n_prime_ + double(k_) * n_prime_ * rows_.cols();
    std::vector<double> sizes;
    for (int iteration = adaptive_kept_ ? first_iteration_ : 0;
         iteration < options_.adaptive_iterations; ++iteration) {
      Progress::check_interrupt();
      keep_before_pass(1, n_prime_, iteration);
      Stopwatch clock;
      auto models = truncated(refitter_.fit(result_.labels, widest, &sizes),
                              std::vector<int>(std::size_t(k_), widest));
      truncate(models, allocate(models, sizes, budget, rows_.cols()));
      const double energy = classify(rows_, models, widest, result_.labels, errors_);
      refill_empty(rows_, result_.labels, errors_, k_);
      result_.log.push_back(gemm_log(rows_, models, widest, clock.seconds(), energy, "adaptive"));
      progress_->add(1, 1);
    }
    // Final representatives for the final classification, same allocation.
    auto models = truncated(refitter_.fit(result_.labels, widest, &sizes),
                            std::vector<int>(std::size_t(k_), widest));
    truncate(models, allocate(models, sizes, budget, rows_.cols()));
    result_.models = std::move(models);
    return std::move(result_);
  }

  const Rows& rows_;
  const CpcaOptions& options_;
  const int n_prime_, k_;
  const PartKeeper* keep_;  // null once keeping failed, on every rank alike
  Refitter refitter_;
  std::vector<double> errors_;
  CpcaResult result_;
  bool resumed_ = false, adaptive_kept_ = false;
  int first_component_ = 1, first_iteration_ = 0, sequence_ = 0;
  Stopwatch since_kept_;
  std::optional<Progress> progress_;
};

}  // namespace

CpcaResult cpca(const Rows& rows, const CpcaOptions& options) {
  if (options.components < 0) throw Error("CPCA: negative component count");
  return CpcaRun(rows, options).run();
}

}  // namespace prt::clustering
