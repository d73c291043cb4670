// Distributed clustering equals the single-process result bit for bit: ranks
// are simulated by threads sharing an in-process Communicator, each holding a
// shard of whole segments, and LBG, iterative and adaptive CPCA and the
// segment sums are compared with one process on the whole signal.
#include <algorithm>
#include <catch2/catch.hpp>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <random>
#include <string>
#include <thread>

#include "../common/thread_communicator.hpp"
#include "prt/checkpoint.hpp"
#include "prt/clustering.hpp"
#include "prt/communicator_parts.hpp"
#include "prt/segment_sum.hpp"

using namespace prt;
using prt::test::ThreadCommunicator;
using prt::test::ThreadGroup;

namespace {

// Rows around a few centres, so clusters are real and ties are rare.
MatrixXfRow clustered_rows(Eigen::Index rows, Eigen::Index cols, int centres) {
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.f, 0.05f);
  std::uniform_int_distribution<int> pick(0, centres - 1);
  const MatrixXfRow centre = MatrixXfRow::Random(centres, cols);
  MatrixXfRow x(rows, cols);
  for (Eigen::Index p = 0; p < rows; ++p) {
    x.row(p) = centre.row(pick(rng));
    for (Eigen::Index d = 0; d < cols; ++d) x(p, d) += noise(rng);
  }
  return x;
}

// Runs `work(rows)` on `ranks` threads, each with its shard of x.
template <class Work>
void on_ranks(const MatrixXfRow& x, int ranks, const Work& work) {
  ThreadGroup group(ranks);
  std::vector<std::thread> threads;
  for (int r = 0; r < ranks; ++r)
    threads.emplace_back([&, r] {
      ThreadCommunicator comm(group, r);
      const Shard shard = shard_of(x.rows(), r, ranks);
      const MatrixXfRow local = x.middleRows(shard.first, shard.rows());
      work(r, clustering::Rows(local, parts_over(comm, shard)));
    });
  for (auto& t : threads) t.join();
}

// The ranks' CPCA results, in rank order, are the one-process result: the
// same models bit for bit, and their labels together are its labels.
void check_same_as_one_process(const std::vector<clustering::CpcaResult>& results,
                               const clustering::CpcaResult& one) {
  std::vector<std::int32_t> labels;
  for (const auto& result : results) {
    labels.insert(labels.end(), result.labels.begin(), result.labels.end());
    REQUIRE(result.models.size() == one.models.size());
    for (std::size_t k = 0; k < one.models.size(); ++k) {
      CHECK(result.models[k].mean == one.models[k].mean);
      CHECK(result.models[k].basis == one.models[k].basis);
    }
  }
  CHECK(labels == one.labels);
}

}  // namespace

TEST_CASE("segment sums are the same bits on any number of ranks", "[distributed]") {
  const Eigen::Index total = 11 * kSegmentRows + 123;  // 12 segments, the last short
  std::vector<double> values(static_cast<std::size_t>(total));
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uniform(-1e3, 1e3);
  for (double& v : values) v = uniform(rng) * std::pow(10.0, int(rng() % 12) - 6);
  auto partial_of = [&](Eigen::Index first) {
    return [&, first](Eigen::Index s) {
      double t = 0;
      for (Eigen::Index p = segment_begin(s); p < segment_end(s, total); ++p)
        t += values[std::size_t(p)];
      (void)first;
      return std::vector<double>{t, 1.0};
    };
  };
  const auto one = segment_sum(whole(total), partial_of(0), solo());
  REQUIRE(one.size() == 2);
  CHECK(one[1] == 12);
  for (int ranks : {2, 3, 5, 12, 13}) {  // 13: a rank with no segment
    ThreadGroup group(ranks);
    std::vector<std::vector<double>> results(static_cast<std::size_t>(ranks));
    std::vector<std::thread> threads;
    for (int r = 0; r < ranks; ++r)
      threads.emplace_back([&, r] {
        ThreadCommunicator comm(group, r);
        results[std::size_t(r)] = segment_sum(shard_of(total, r, ranks), partial_of(0), comm);
      });
    for (auto& t : threads) t.join();
    for (const auto& result : results) CHECK(result == one);  // exactly, not approximately
  }
  // A shard that does not hold whole segments is refused.
  CHECK_THROWS(segment_sum({100, total, total}, partial_of(0), solo()));
  // Shards that leave a segment to no rank: rank 0 finds it out when it adds
  // the roots, and every rank gets its message (none waits for a sum).
  {
    const int ranks = 3;
    ThreadGroup group(ranks);
    std::vector<std::string> errors(static_cast<std::size_t>(ranks));
    std::vector<std::thread> threads;
    for (int r = 0; r < ranks; ++r)
      threads.emplace_back([&, r] {
        ThreadCommunicator comm(group, r);
        Shard shard = shard_of(total, r, ranks);
        if (r == 1) shard.last = shard.first;  // rank 1 drops its segments
        try {
          segment_sum(shard, partial_of(0), comm);
        } catch (const std::exception& e) {
          errors[std::size_t(r)] = e.what();
        }
      });
    for (auto& t : threads) t.join();
    for (const auto& error : errors) CHECK_THAT(error, Catch::Contains("no rank computed segment"));
  }
}

TEST_CASE("distributed LBG and CPCA equal one process bit for bit", "[distributed]") {
  const MatrixXfRow x = clustered_rows(3 * kSegmentRows + 1000, 12, 9);
  for (auto init : {clustering::Init::kmeans_plus_plus, clustering::Init::hyperbox})
    for (auto method : {clustering::Method::static_pca, clustering::Method::iterative,
                        clustering::Method::adaptive}) {
      clustering::CpcaOptions options;
      options.lbg.clusters = 12;
      options.lbg.init = init;
      options.method = method;
      options.components = 3;
      options.iterations_per_component = 3;
      options.adaptive_iterations = 2;
      const clustering::CpcaResult one = clustering::cpca(x, options);
      for (int ranks : {2, 3}) {
        INFO("ranks " << ranks << ", method " << int(method) << ", init " << int(init));
        std::vector<clustering::CpcaResult> results(static_cast<std::size_t>(ranks));
        on_ranks(x, ranks, [&](int r, const clustering::Rows& rows) {
          results[std::size_t(r)] = clustering::cpca(rows, options);
        });
        check_same_as_one_process(results, one);
      }
    }
}

TEST_CASE("compressed rows gather on rank 0 in vertex order", "[distributed]") {
  const MatrixXfRow x = clustered_rows(2 * kSegmentRows + 77, 6, 4);
  std::vector<std::int32_t> labels(std::size_t(x.rows()));
  for (std::size_t p = 0; p < labels.size(); ++p) labels[p] = std::int32_t(p % 4);
  const auto models = clustering::fit_models(clustering::Rows(x), labels, 4, {2, 2, 2, 2});
  const CompressedTransfer one = clustering::assemble(x, labels, models, "test");
  on_ranks(x, 3, [&](int r, const clustering::Rows& rows) {
    const std::vector<std::int32_t> local(labels.begin() + rows.shard.first,
                                          labels.begin() + rows.shard.last);
    const auto shared = clustering::fit_models(rows, local, 4, {2, 2, 2, 2});
    CompressedTransfer c = clustering::assemble(rows.x, local, shared, "test");
    clustering::gather_rows(rows, c);
    if (r == 0) {
      CHECK(c.cluster_of_vertex == one.cluster_of_vertex);
      CHECK(c.weights == one.weights);
      CHECK(c.means == one.means);
    } else {
      CHECK(c.vertices() == rows.local());
    }
  });
}

TEST_CASE("small clusters (Gram matrices) and large ones (scatter) fit alike on any rank count",
          "[distributed][clustering]") {
  // Clusters 0-39 have 25 members in 30 dimensions (fitted from their Gram
  // matrix) and 41-42 ~155 (from their scatter), members gathered across
  // ranks; 40 has too many to gather (its scatter summed over segments).
  const MatrixXfRow x = clustered_rows(2 * kSegmentRows + 77, 30, 5);
  std::vector<std::int32_t> labels(std::size_t(x.rows()));
  for (std::size_t p = 0; p < labels.size(); ++p)
    labels[p] = std::int32_t(p < 1000 ? p % 40 : p % 100 < 2 ? 41 + p % 100 : 40);
  const auto points = [&](int k) { return std::count(labels.begin(), labels.end(), k); };
  const auto gathered = clustering::kGatheredPointsPerDimension * 30;
  REQUIRE(points(41) > 30);
  REQUIRE(points(41) <= gathered);
  REQUIRE(points(40) > gathered);
  // Members of small clusters on every rank: spread them over the shards.
  std::swap_ranges(labels.begin() + 500, labels.begin() + 1000, labels.end() - 500);
  const std::vector<int> components(43, 4);
  const auto one = clustering::fit_models(clustering::Rows(x), labels, 43, components);
  for (int ranks : {2, 3}) {
    on_ranks(x, ranks, [&](int, const clustering::Rows& rows) {
      const std::vector<std::int32_t> local(labels.begin() + rows.shard.first,
                                            labels.begin() + rows.shard.last);
      const auto shared = clustering::fit_models(rows, local, 43, components);
      REQUIRE(shared.size() == one.size());
      for (std::size_t k = 0; k < one.size(); ++k) {
        CHECK(shared[k].mean == one[k].mean);
        CHECK(shared[k].basis == one[k].basis);
        CHECK(shared[k].eigenvalues == one[k].eigenvalues);
      }
    });
  }
}

TEST_CASE("distributed LBG keeps each rank's labels and resumes to the same clusters",
          "[distributed][checkpoint]") {
  const MatrixXfRow x = clustered_rows(3 * kSegmentRows + 1000, 12, 9);
  clustering::LbgOptions options;
  options.clusters = 16;
  options.tolerance = 0;
  options.max_iterations = 9;
  const clustering::Clusters one = clustering::lbg(x, options);
  for (int ranks : {1, 3}) {
    INFO("ranks " << ranks);
    const auto output = std::filesystem::temp_directory_path() / "prt_lbg_kept" / "bake.h5";
    std::filesystem::remove_all(output.parent_path());
    std::filesystem::create_directories(output.parent_path());
    const CheckpointStore store(output, "key", "test");
    clustering::LbgOptions kept = options;
    kept.keep = &store;
    kept.keep_seconds = 0;    // after every iteration
    kept.max_iterations = 4;  // "killed" after iteration 4: its state is kept
    on_ranks(x, ranks, [&](int, const clustering::Rows& rows) { clustering::lbg(rows, kept); });
    REQUIRE(store.has("lbg.state"));
    for (int r = 0; r < ranks; ++r) {  // each rank's labels, under its shard's rows
      const Shard shard = shard_of(x.rows(), r, ranks);
      CHECK(store.has("lbg.labels.0.rows-" + std::to_string(shard.first) + "-" +
                      std::to_string(shard.last)));
    }
    kept.max_iterations = options.max_iterations;
    std::vector<clustering::Clusters> results(static_cast<std::size_t>(ranks));
    on_ranks(x, ranks, [&](int r, const clustering::Rows& rows) {
      results[std::size_t(r)] = clustering::lbg(rows, kept);
    });
    std::vector<std::int32_t> labels;
    for (const auto& result : results) {
      labels.insert(labels.end(), result.labels.begin(), result.labels.end());
      CHECK(result.means == one.means);
      CHECK(result.energy == one.energy);
      CHECK(result.iterations == one.iterations);
      CHECK(result.log.size() < one.log.size());  // it resumed: fewer iterations ran
    }
    CHECK(labels == one.labels);
    // Another rank count finds no labels for its shards and starts afresh, to
    // the same clusters.
    if (ranks > 1) {
      kept.keep_seconds = 1e9;
      on_ranks(x, 2, [&](int r, const clustering::Rows& rows) {
        const clustering::Clusters again = clustering::lbg(rows, kept);
        CHECK(again.means == one.means);
        if (r == 0) CHECK(again.log.size() == one.log.size());
      });
    }
    store.remove();
  }
}

TEST_CASE("distributed CPCA keeps each rank's labels before a pass and resumes to the same result",
          "[distributed][checkpoint]") {
  const MatrixXfRow x = clustered_rows(3 * kSegmentRows + 1000, 12, 9);
  for (auto method : {clustering::Method::iterative, clustering::Method::adaptive}) {
    clustering::CpcaOptions options;
    options.lbg.clusters = 12;
    options.method = method;
    options.components = 3;
    options.iterations_per_component = 2;
    options.adaptive_iterations = 2;
    const clustering::CpcaResult one = clustering::cpca(x, options);
    const auto output = std::filesystem::temp_directory_path() / "prt_cpca_kept" / "bake.h5";
    std::filesystem::remove_all(output.parent_path());
    std::filesystem::create_directories(output.parent_path());
    const CheckpointStore store(output, "key", "test");
    clustering::CpcaOptions kept = options;
    kept.lbg.keep = &store;
    kept.lbg.keep_seconds = 0;  // before every pass
    const int ranks = 3;
    // The first run keeps a state before each pass; the rerun resumes from
    // the last (as after a kill before the last pass) and must end the same.
    for (int run = 0; run < 2; ++run) {
      INFO("method " << int(method) << ", run " << run);
      std::vector<clustering::CpcaResult> results(static_cast<std::size_t>(ranks));
      on_ranks(x, ranks, [&](int r, const clustering::Rows& rows) {
        results[std::size_t(r)] = clustering::cpca(rows, kept);
      });
      REQUIRE(store.has("cpca.state"));
      const Shard last = shard_of(x.rows(), ranks - 1, ranks);
      const std::string shard_rows =
          ".rows-" + std::to_string(last.first) + "-" + std::to_string(last.last);
      CHECK((store.has("cpca.labels.0" + shard_rows) || store.has("cpca.labels.1" + shard_rows)));
      check_same_as_one_process(results, one);
      if (run == 1)  // LBG and passes skipped
        for (const auto& result : results) CHECK(result.log.size() < one.log.size());
    }
    store.remove();
  }
}
