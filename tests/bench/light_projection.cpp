// Light projection against the matrix product of its shape, in one run.
//
//   bench_light [order] [map.exr ...]     (defaults: 10, a 1024x512 map and the Blender maps)
//
// For each map: the time to project it onto order-`order` SH (the separable
// transform the SH basis uses), next to the float GEMM of the same shape
// (3 x pixels) by (pixels x order^2) on every core: the cost of projecting
// the texels through basis values that were already evaluated. Limit
// (issue 12): projection <= 1.5x that GEMM. Then the viewer's rotated light
// (rotating coefficients) against the 16.7 ms of a 60 Hz frame.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "prt/environment.hpp"
#include "prt/progress.hpp"
#include "prt/sh.hpp"
#include "prt/sh_rotation.hpp"
#include "timing.hpp"

#ifndef PRT_SOURCE_DIR
#define PRT_SOURCE_DIR "."
#endif

namespace {

using prt::bench::median_seconds;

// (3 x pixels) * (pixels x n) in float, blocked over pixels on every core,
// with a fixed-order reduction of the per-block results.
double gemm_seconds(Eigen::Index pixels, Eigen::Index n, int repeats) {
  const Eigen::MatrixXf texels = Eigen::MatrixXf::Random(3, pixels);
  const Eigen::MatrixXf values = Eigen::MatrixXf::Random(pixels, n);
  constexpr Eigen::Index kBlock = 8192;
  const Eigen::Index blocks = (pixels + kBlock - 1) / kBlock;
  std::vector<Eigen::MatrixXf> partial(blocks);
  return median_seconds(repeats, [&] {
    tbb::parallel_for(Eigen::Index(0), blocks, [&](Eigen::Index b) {
      const Eigen::Index begin = b * kBlock, count = std::min(kBlock, pixels - begin);
      partial[b].noalias() = texels.middleCols(begin, count) * values.middleRows(begin, count);
    });
    Eigen::MatrixXf sum = partial[0];
    for (Eigen::Index b = 1; b < blocks; ++b) sum += partial[b];
  });
}

}  // namespace

int main(int argc, char** argv) {
  using namespace prt;
  const int order = argc > 1 ? std::stoi(argv[1]) : 10;
  std::vector<std::string> maps;
  for (int i = 2; i < argc; ++i) maps.push_back(argv[i]);
  if (maps.empty())
    for (const char* name : {"courtyard", "sunset", "forest", "night"})
      maps.push_back(std::string(PRT_SOURCE_DIR) + "/data/hdri/" + name + ".exr");
  const int repeats = 15;
  double worst = 0, worst_project = 0, worst_gemm = 0;
  auto row = [&](const std::string& name, int width, int height, const float* rgb) {
    const double project = median_seconds(repeats, [&] {
      const Eigen::MatrixX3d light = sh::project_equirect(order, width, height, rgb);
      if (!light.allFinite()) std::puts("non-finite");
    });
    const double gemm = gemm_seconds(Eigen::Index(width) * height, order * order, repeats);
    if (project / gemm > worst) worst = project / gemm, worst_project = project, worst_gemm = gemm;
    std::printf("%-22s %5dx%-5d project %8.3f ms   GEMM 3x%dx%d %8.3f ms   ratio %5.2f\n",
                name.c_str(), width, height, 1e3 * project, width * height, order * order,
                1e3 * gemm, project / gemm);
  };
  {  // a 1024 x 512 map of noise
    std::vector<float> rgb(std::size_t(1024) * 512 * 3);
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(0.f, 4.f);
    for (float& v : rgb) v = u(rng);
    row("noise", 1024, 512, rgb.data());
  }
  for (const std::string& file : maps) {
    const Environment env = Environment::load(file);
    row(file.substr(file.find_last_of('/') + 1), env.width(), env.height(), env.pixels().data());
  }
  // The viewer turning the light: rotate the coefficients (block-diagonal).
  const Eigen::MatrixX3d light = Eigen::MatrixX3d::Random(order * order, 3);
  Eigen::MatrixXd rotated(order * order, 3);
  double angle = 0;
  const double turn = median_seconds(200, [&] {
    angle += 0.01;
    const Eigen::Matrix3d r = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).matrix();
    sh::Rotation(order, r).apply(light, rotated);
  });
  std::printf("rotated light (viewer): %.3f ms of a 16.7 ms frame\n", 1e3 * turn);
  std::printf(
      "PERF|light projection, equirect -> SH order %d (worst map)|%.2f ms|GEMM of its "
      "shape %.2f ms|%.3f|1.5|%s\n",
      order, 1e3 * worst_project, 1e3 * worst_gemm, worst, worst <= 1.5 ? "PASS" : "FAIL");
  std::printf("PERF|rotated light in the viewer|%.4g ms|60 Hz frame 16.7 ms|%.4f|1|%s\n",
              1e3 * turn, turn / (1.0 / 60), turn <= 1.0 / 60 ? "PASS" : "FAIL");
  return 0;
}
