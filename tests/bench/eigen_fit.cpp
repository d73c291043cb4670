// Eigentransport fitting in bounded memory, against one GEMM of its size.
//
//   bench_eigen [mesh.off] [cube resolution] [d]      defaults: bunny00.off 32 48
//
// Traces the mesh on a 6 x R x R cube map keeping only visibility bits, fits
// the eigentransport plug-in (randomized SVD streamed from the bits), and
// prints the fit time next to one double GEMM of the shape v x s x (d + 10)
// (the product C Omega of one pass, dense), and the peak resident memory
// against the size a dense double v x s transport matrix would take.
#include <sys/resource.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstdio>
#include <string>
#include <vector>

#include "prt/basis.hpp"
#include "prt/mesh.hpp"
#include "prt/progress.hpp"
#include "prt/registry.hpp"
#include "prt/transport.hpp"
#include "timing.hpp"

#ifndef PRT_SOURCE_DIR
#define PRT_SOURCE_DIR "."
#endif

namespace {
double visible_fraction(const prt::VisibilityBits& visibility) {
  double visible = 0;
  for (std::size_t v = 0; v < visibility.vertices(); ++v) visible += visibility.count_visible(v);
  return visible / (double(visibility.vertices()) * double(visibility.directions()));
}
}  // namespace

int main(int argc, char** argv) {
  using namespace prt;
  const std::string file =
      argc > 1 ? argv[1] : std::string(PRT_SOURCE_DIR) + "/data/meshes/bunny00.off";
  const int resolution = argc > 2 ? std::stoi(argv[2]) : 32;
  const int d = argc > 3 ? std::stoi(argv[3]) : 48;
  const Mesh mesh = load_mesh(file);
  const DirectionSet set = DirectionSet::cubemap(resolution);
  std::printf("%s: %zu vertices, %lld directions (6 x %d x %d), d = %d\n", file.c_str(),
              mesh.vertex_count(), (long long)set.size(), resolution, resolution, d);
  TransportOptions options;
  options.keep_visibility = true;
  Stopwatch trace_clock;
  const TransportResult traced =
      diffuse_transfer(mesh, set, Eigen::MatrixXd(set.size(), 0), options, nullptr);
  const double trace_seconds = trace_clock.seconds();

  PluginRegistry registry(PluginRegistry::default_directories());
  Params params;
  params.set("d", std::int64_t(d));
  // One fit for the peak memory of trace + fit (the timed fits follow).
  registry.create<Basis>("eigen", params)->fit({&mesh, &set, &traced.visibility});
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);  // peak of trace + fit, before the GEMM reference

  // The GEMM of the fit's shape on every core (row blocks over TBB, as the
  // fit's own passes run), double as the fit. Three GEMMs and three fits
  // alternate, each fit of a fresh plug-in (no buffers kept from the last).
  const Eigen::MatrixXd a = Eigen::MatrixXd::Random(mesh.vertex_count(), set.size());
  const Eigen::MatrixXd b = Eigen::MatrixXd::Random(set.size(), d + 10);
  Eigen::MatrixXd c(a.rows(), b.cols());
  const auto [fit_seconds, gemm_seconds] = bench::alternating_median_seconds(
      3,
      [&] {
        auto fresh = registry.create<Basis>("eigen", params);
        fresh->fit({&mesh, &set, &traced.visibility});
      },
      [&] {
        tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, a.rows(), 256),
                          [&](const auto& range) {
                            c.middleRows(range.begin(), range.size()).noalias() =
                                a.middleRows(range.begin(), range.size()) * b;
                          });
      });

  const double dense_gb = double(mesh.vertex_count()) * set.size() * 8 / 1e9;
  std::printf("trace (bits only)   : %8.3f s\n", trace_seconds);
  std::printf("fit (randomized SVD): %8.3f s   = %.2f x one GEMM %zux%lldx%d (%.3f s, all cores)\n",
              fit_seconds, fit_seconds / gemm_seconds, mesh.vertex_count(), (long long)set.size(),
              d + 10, gemm_seconds);
  std::printf("visibility bits     : %8.1f MB\n",
              double(mesh.vertex_count()) * ((set.size() + 63) / 64) * 8 / 1e6);
  std::printf("peak RSS, trace+fit : %8.1f MB (a dense double v x s transport matrix: %.2f GB)\n",
              usage.ru_maxrss / 1024.0, dense_gb);
  std::printf(
      "the fit makes six products with C (C Omega, two power iterations of C^T Q and C Q, "
      "Q^T C), each over the visible pairs only (%.0f%% of v x s here)\n",
      100.0 * visible_fraction(traced.visibility));
  const double ratio = fit_seconds / gemm_seconds;
  std::printf("PERF|eigentransport fit %zux%lld d=%d|%.3f s|GEMM of its shape %.3f s|%.2f|3|%s\n",
              mesh.vertex_count(), (long long)set.size(), d, fit_seconds, gemm_seconds, ratio,
              ratio <= 3 ? "PASS" : "FAIL");
  std::printf(
      "PERF|eigentransport peak memory|%.0f MB|dense transport matrix %.0f MB|%.3f|0.25|%s\n",
      usage.ru_maxrss / 1024.0, dense_gb * 1e3, usage.ru_maxrss / 1024.0 / (dense_gb * 1e3),
      usage.ru_maxrss / 1024.0 <= 0.25 * dense_gb * 1e3 ? "PASS" : "FAIL");
  return c.allFinite() ? 0 : 1;
}
