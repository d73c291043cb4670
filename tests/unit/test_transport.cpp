#include <tbb/global_control.h>

#include <catch2/catch.hpp>

#include "../common/scenes.hpp"
#include "prt/environment.hpp"
#include "prt/ground_truth.hpp"
#include "prt/mesh.hpp"
#include "prt/sh.hpp"
#include "prt/transport.hpp"

using namespace prt;

namespace {
Eigen::MatrixXd sh_projection(int order, const DirectionSet& set) {
  return set.weights.asDiagonal() * sh::evaluate(order, set.directions);
}
}  // namespace

TEST_CASE("shadowed transfer of a convex sphere is the clamped cosine rotated to the normal",
          "[transport]") {
  const int order = 10;
  const Mesh sphere = make_sphere(2);
  const DirectionSet set = DirectionSet::fibonacci(16384);
  const TransportResult r =
      diffuse_transfer(sphere, set, sh_projection(order, set), {true, true}, nullptr);
  REQUIRE(r.transfer.coefficients.allFinite());
  double worst = 0;
  for (std::size_t v = 0; v < sphere.vertex_count(); ++v) {
    const Eigen::VectorXd exact =
        sh::clamped_cosine(order, sphere.normals[v].cast<double>()) / M_PI;
    const Eigen::VectorXd baked =
        r.transfer.coefficients.row(static_cast<Eigen::Index>(v)).transpose().cast<double>();
    worst = std::max(worst, (baked - exact).cwiseAbs().maxCoeff());
    // No ray of a convex object is blocked: every upper-hemisphere ray escapes.
    const Eigen::Vector3d n = sphere.normals[v].cast<double>();
    std::size_t above = 0;
    for (Eigen::Index k = 0; k < set.size(); ++k) above += n.dot(set.directions.row(k)) > 0;
    REQUIRE(r.visibility.count_visible(v) == above);
  }
  CHECK(worst < 2e-3);  // quadrature error of the clamped cosine's kink
}

TEST_CASE("all rays blocked gives zero transfer; unshadowed ignores occluders",
          "[transport][extremes]") {
  Mesh inside_out = make_box();
  for (auto& n : inside_out.normals) n = -n;  // every ray heads into the box
  const DirectionSet set = DirectionSet::fibonacci(512);
  const auto p = sh_projection(4, set);
  const TransportResult blocked = diffuse_transfer(inside_out, set, p, {true, false}, nullptr);
  CHECK(blocked.transfer.coefficients.cwiseAbs().maxCoeff() == 0.0f);
  CHECK(blocked.rays_cast > 0);
  const TransportResult open = diffuse_transfer(inside_out, set, p, {false, false}, nullptr);
  CHECK(open.transfer.coefficients.col(0).minCoeff() > 0.2f);
  CHECK(open.rays_cast == 0);
}

TEST_CASE("a plane sees nothing above it: shadowed equals unshadowed", "[transport]") {
  const Mesh plane = make_plane(4);
  const DirectionSet set = DirectionSet::fibonacci(1024);
  const auto p = sh_projection(6, set);
  const auto a = diffuse_transfer(plane, set, p, {true, false}, nullptr);
  const auto b = diffuse_transfer(plane, set, p, {false, false}, nullptr);
  CHECK((a.transfer.coefficients - b.transfer.coefficients).cwiseAbs().maxCoeff() == 0.0f);
}

TEST_CASE("transfer is bit-identical across runs and thread counts", "[transport]") {
  // A plane under the sphere, so some rays are blocked.
  const Mesh scene = test::sphere_over_plane(3, 8, 6.0f, -1.2f);
  const auto base = static_cast<std::uint32_t>(make_sphere(3).vertex_count());
  const DirectionSet set = DirectionSet::stratified(700, 9);
  const auto p = sh_projection(5, set);
  const auto two = diffuse_transfer(scene, set, p, {true, false}, nullptr);
  TransportResult one;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = diffuse_transfer(scene, set, p, {true, false}, nullptr);
  }
  CHECK(one.transfer.coefficients == two.transfer.coefficients);
  CHECK(one.rays_cast == two.rays_cast);
  CHECK(trace_only(scene, set, nullptr) == two.rays_cast);
  // The plane's vertices under the sphere are darker than at its rim.
  const float centre = two.transfer.coefficients(base + 4 * 9 + 4, 0);
  const float corner = two.transfer.coefficients(base, 0);
  CHECK(centre < corner);
}

TEST_CASE("ground truth under constant unit light is exactly 1 on a convex object",
          "[transport][ground-truth]") {
  const Mesh sphere = make_sphere(1);
  const Environment white = Environment::constant({1, 1, 1});
  const Eigen::MatrixX3f radiance = ground_truth_radiance(sphere, white, 64, 1, nullptr);
  CHECK((radiance.array() - 1.0f).abs().maxCoeff() < 1e-6f);
  Mesh inside_out = make_box();
  for (auto& n : inside_out.normals) n = -n;
  CHECK(ground_truth_radiance(inside_out, white, 64, 1, nullptr).cwiseAbs().maxCoeff() == 0.0f);
}

TEST_CASE("ground truth handles radiance from 1e-6 to 1e6 linearly", "[ground-truth][extremes]") {
  const Mesh sphere = make_sphere(1);
  for (float scale : {1e-6f, 1e6f}) {
    const Environment env = Environment::constant({scale, scale, scale});
    const Eigen::MatrixX3f radiance = ground_truth_radiance(sphere, env, 16, 1, nullptr);
    CHECK(((radiance.array() / scale) - 1.0f).abs().maxCoeff() < 1e-5f);
  }
}
