// Compression speed against the matrix products it is made of, in one run.
//
//   bench_compress [bake.h5] [clusters] [components] [method] [wall limit, s]
//
// For every iteration of LBG and of iterative/adaptive CPCA it prints the
// iteration's wall time next to the time of one float GEMM of the same shape
// (rows x inner x cols: the data times all means and representatives), and
// the ratio. The GEMM does the multiply-adds of an iteration's
// classification (LBG's is one; CPCA's packed pass does them faster).
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "prt/bake_file.hpp"
#include "prt/clustering.hpp"
#include "prt/progress.hpp"

#ifndef PRT_SOURCE_DIR
#define PRT_SOURCE_DIR "."
#endif

namespace {
// Best of three float GEMMs of the shape, on all cores (row blocks over TBB,
// as Eigen alone runs one thread without OpenMP). Each thread writes into a
// buffer of its own, kept across blocks and runs, as LBG's classification
// keeps its products: a fresh result per block would add allocation and page
// faults to the bound.
double gemm_seconds(Eigen::Index rows, Eigen::Index inner, Eigen::Index cols) {
  constexpr Eigen::Index kRows = 512;
  const prt::MatrixXfRow a = prt::MatrixXfRow::Random(rows, inner);
  const Eigen::MatrixXf b = Eigen::MatrixXf::Random(inner, cols);
  tbb::enumerable_thread_specific<Eigen::MatrixXf> products(
      [&] { return Eigen::MatrixXf::Zero(kRows, cols); });
  double best = 1e30;
  for (int r = 0; r < 3; ++r) {
    prt::Stopwatch clock;
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, rows, kRows), [&](const auto& range) {
      for (Eigen::Index first = range.begin(); first < range.end(); first += kRows) {
        const Eigen::Index count = std::min(kRows, range.end() - first);
        products.local().topRows(count).noalias() = a.middleRows(first, count) * b;
      }
    });
    best = std::min(best, clock.seconds());
  }
  float sink = 0;
  for (const auto& c : products) sink += c(0, 0);
  if (!(sink == sink)) std::puts("");  // keeps the products observable
  return best;
}
}  // namespace

int main(int argc, char** argv) {
  using namespace prt;
  const std::string file = argc > 1 ? argv[1] : std::string(PRT_SOURCE_DIR) + "/out/bunny.h5";
  clustering::CpcaOptions options;
  options.lbg.clusters = argc > 2 ? std::stoi(argv[2]) : 256;
  options.components = argc > 3 ? std::stoi(argv[3]) : 8;
  const std::string method = argc > 4 ? argv[4] : "iterative";
  const double wall_limit = argc > 5 ? std::stod(argv[5]) : 0;  // seconds, 0: none
  options.method = method == "static"     ? clustering::Method::static_pca
                   : method == "adaptive" ? clustering::Method::adaptive
                                          : clustering::Method::iterative;
  options.lbg.init = clustering::Init::kmeans_plus_plus;
  const BakeData data = read_bake(file);
  const MatrixXfRow& x = data.transfer.coefficients;
  std::printf("%s: %lld x %lld, %d clusters, n' = %d, %s CPCA\n", file.c_str(), (long long)x.rows(),
              (long long)x.cols(), options.lbg.clusters, options.components, method.c_str());
  Stopwatch total;
  const auto result = clustering::cpca(x, options);
  const double seconds = total.seconds();
  std::printf("%-10s %4s %10s %22s %10s %8s\n", "stage", "#", "iter s", "GEMM shape", "GEMM s",
              "ratio");
  double sum_iterations = 0, sum_gemm = 0;
  std::vector<double> ratios;
  int index = 0;
  for (const auto& it : result.log) {
    const double g = gemm_seconds(it.rows, it.inner, it.cols);
    char shape[64];
    std::snprintf(shape, sizeof shape, "%lldx%lldx%lld", (long long)it.rows, (long long)it.inner,
                  (long long)it.cols);
    std::printf("%-10s %4d %10.4f %22s %10.4f %8.2f\n", it.stage.c_str(), index++, it.seconds,
                shape, g, it.seconds / g);
    sum_iterations += it.seconds;
    sum_gemm += g;
    if (it.stage != "init") ratios.push_back(it.seconds / g);  // LBG and CPCA iterations
  }
  std::printf("total encode %.3f s; iterations %.3f s vs their GEMMs %.3f s: ratio %.2f\n", seconds,
              sum_iterations, sum_gemm, sum_iterations / sum_gemm);
  // The limit applies to every iteration; the median shows the typical one.
  std::sort(ratios.begin(), ratios.end());
  const double median = ratios.empty() ? 0 : ratios[ratios.size() / 2];
  const double worst = ratios.empty() ? 0 : ratios.back();
  const std::string label = method + " CPCA iteration, " + std::to_string(x.cols()) + "-dim";
  std::printf("PERF|%s (median; worst %.2f)|%.3f s|GEMM of its shape %.3f s|%.2f|1.3|%s\n",
              label.c_str(), worst, sum_iterations / std::max<std::size_t>(1, result.log.size()),
              sum_gemm / std::max<std::size_t>(1, result.log.size()), median,
              median <= 1.3 ? "PASS" : "FAIL");
  if (wall_limit > 0)
    std::printf("PERF|%s CPCA encode, %lld-dim, %d x %d|%.1f s|-|%.2f|%.0f s|%s\n", method.c_str(),
                (long long)x.cols(), options.lbg.clusters, options.components, seconds,
                seconds / wall_limit, wall_limit, seconds <= wall_limit ? "PASS" : "FAIL");
  return 0;
}
