// Point lights: the nearest-direction rule of lattice bases, exact evaluation
// for continuous ones, brute-force re-projection, the ground truth's shadow
// rays up to the light, and the scene's [[lighting.point]] tables.
#include <catch2/catch.hpp>

#include "prt/basis.hpp"
#include "prt/compressor.hpp"
#include "prt/environment.hpp"
#include "prt/error.hpp"
#include "prt/point_lights.hpp"
#include "prt/registry.hpp"
#include "prt/scene.hpp"
#include "prt/sh.hpp"

using namespace prt;

namespace {

// Unshadowed convex sphere: T(w) = max(n . w, 0) / pi, projected and kept whole.
CompressedTransfer sphere_transfer(const Mesh& sphere, const Basis& basis, const DirectionSet& set,
                                   PluginRegistry& registry) {
  Eigen::MatrixXd samples(sphere.vertex_count(), set.size());
  for (std::size_t v = 0; v < sphere.vertex_count(); ++v)
    for (Eigen::Index k = 0; k < set.size(); ++k)
      samples(v, k) =
          std::max(0.0, sphere.normals[v].cast<double>().dot(set.directions.row(k))) / M_PI;
  TransferSignal t;
  t.coefficients = basis.project(samples, set).cast<float>();
  Params none;
  return registry.create<Compressor>("none", none)->encode(t, nullptr);
}

std::shared_ptr<Basis> make_basis(PluginRegistry& registry, const char* name, const char* key,
                                  std::int64_t value) {
  Params p;
  p.set(key, value);
  return registry.create<Basis>(name, p);
}

}  // namespace

TEST_CASE("a lattice basis shares a point light among its k nearest directions", "[point-light]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  auto haar = make_basis(registry, "haar", "resolution", 8);
  const Mesh sphere = make_sphere(2);
  const DirectionSet lattice = DirectionSet::cubemap(8);
  const CompressedTransfer t = sphere_transfer(sphere, *haar, lattice, registry);
  PointLight light;
  light.position = Eigen::Vector3d(0.3, 40, -0.2);
  const MatrixXfRow decoded = t.decode();
  const Eigen::MatrixXd values = haar->evaluate(lattice.directions);
  for (int k : {1, 4}) {
    const PointLightProjector rule(*haar, k);
    REQUIRE(rule.rule() == PointLightProjector::Rule::nearest);
    const Eigen::MatrixX3f e = point_light_radiance(sphere, t, 1, rule, {light});
    for (std::size_t v = 0; v < sphere.vertex_count(); v += 7) {
      const Eigen::Vector3d w = (light.position - sphere.positions[v].cast<double>()).normalized();
      // The k largest cosines to w, by brute force.
      std::vector<std::pair<double, Eigen::Index>> order;
      for (Eigen::Index s = 0; s < lattice.size(); ++s)
        order.push_back({-lattice.directions.row(s).dot(w), s});
      std::sort(order.begin(), order.end());
      double expected = 0;
      for (int j = 0; j < k; ++j)
        expected += decoded.row(v).cast<double>().dot(values.row(order[j].second)) / k;
      CHECK(e(v, 0) == Approx(expected).margin(1e-5));
    }
  }
}

TEST_CASE("a continuous basis evaluates a point light at its exact direction", "[point-light]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  auto sh = make_basis(registry, "sh", "order", 6);
  const PointLightProjector exact(*sh, 3);
  CHECK(exact.rule() == PointLightProjector::Rule::exact);
  const Mesh sphere = make_sphere(1);
  PointLight light;
  light.position = Eigen::Vector3d(2, 1, 0.5);
  const Eigen::MatrixXd vectors = exact.light_vectors(sphere, light);
  // Radius 0: brute force has one direction, the same.
  const Eigen::MatrixXd brute =
      PointLightProjector::brute_force(*sh, 64).light_vectors(sphere, light);
  CHECK((vectors - brute).cwiseAbs().maxCoeff() < 1e-12);
  for (std::size_t v = 0; v < sphere.vertex_count(); v += 5) {
    Directions w(1, 3);
    w.row(0) = (light.position - sphere.positions[v].cast<double>()).normalized().transpose();
    CHECK((vectors.row(v) - sh::evaluate(6, w)).cwiseAbs().maxCoeff() < 1e-12);
  }
  // A spherical light: brute force averages the cap, which blurs it.
  light.radius = 0.8;
  const Eigen::MatrixXd blurred =
      PointLightProjector::brute_force(*sh, 64).light_vectors(sphere, light);
  CHECK(blurred.allFinite());
  CHECK(blurred.row(0).tail(20).norm() < vectors.row(0).tail(20).norm());
}

TEST_CASE("the point-light ground truth is exact on a convex sphere and shadows up to the light",
          "[point-light][ground-truth]") {
  const Mesh sphere = make_sphere(2);
  PointLight light;
  light.position = Eigen::Vector3d(0, 30, 0);
  light.colour = Eigen::Vector3d(1, 0.5, 0.25);
  light.intensity = 2;
  const Eigen::MatrixX3f truth = ground_truth_point_lights(sphere, {light}, 16, 1);
  for (std::size_t v = 0; v < sphere.vertex_count(); ++v) {
    const Eigen::Vector3d w = (light.position - sphere.positions[v].cast<double>()).normalized();
    const double expected = 2 * std::max(0.0, sphere.normals[v].cast<double>().dot(w)) / M_PI;
    CHECK(truth(v, 0) == Approx(expected).margin(1e-6));
    CHECK(truth(v, 2) == Approx(0.25 * expected).margin(1e-6));
  }
  // An open box's wall at x = -1 faces +x (inward). A light beyond the far
  // wall (x = 3) is blocked by it; a light inside is not blocked by that wall
  // behind it, because rays stop at the light.
  const Mesh box = make_generated("open-box", 2);
  auto left_wall = [&](const Eigen::MatrixX3f& radiance) {
    double most = 0;
    for (std::size_t v = 0; v < box.vertex_count(); ++v)
      if (box.normals[v].x() > 0.9f && std::abs(box.positions[v].y()) < 0.8f &&
          std::abs(box.positions[v].z()) < 0.8f)
        most = std::max(most, double(radiance.row(v).maxCoeff()));
    return most;
  };
  light.position = Eigen::Vector3d(3, 0, 0);
  CHECK(left_wall(ground_truth_point_lights(box, {light}, 16, 1)) == 0);
  light.position = Eigen::Vector3d(0.5, 0, 0);
  CHECK(left_wall(ground_truth_point_lights(box, {light}, 16, 1)) > 0.1);
}

TEST_CASE("[[lighting.point]] tables are read, checked and may stand alone",
          "[point-light][scene]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  const std::string head = "[mesh]\ngenerate = \"sphere\"\n[lighting]\n";
  const SceneSpec s = SceneSpec::parse(
      head +
          "nearest = 2\n[[lighting.point]]\nposition = [1, 2, 3]\nintensity = 4\n"
          "[[lighting.point]]\nposition = [0, 0, 5]\ncolour = [1, 0, 0]\nradius = 0.5\n",
      "points.toml", registry);
  REQUIRE(s.point_lights.size() == 2);
  CHECK(s.point_lights[0].position == Eigen::Vector3d(1, 2, 3));
  CHECK(s.point_lights[0].power() == Eigen::Vector3d(4, 4, 4));
  CHECK(s.point_lights[1].radius == 0.5);
  CHECK(s.lighting.get_int("nearest") == 2);
  CHECK(s.load_environment().radiance(Eigen::Vector3d::UnitY()).norm() == 0);  // alone: black
  auto message = [&](const std::string& text) {
    try {
      SceneSpec::parse(head + text, "points.toml", registry);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK_THAT(message("[[lighting.point]]\nintensity = 1\n"),
             Catch::Contains("points.toml:") && Catch::Contains("\"position\" is required"));
  CHECK_THAT(message("[[lighting.point]]\nposition = [1, 2]\n"), Catch::Contains("position"));
  CHECK_THAT(message("[[lighting.point]]\nposition = [1, 2, 3]\nbrightness = 2\n"),
             Catch::Contains("brightness"));
  CHECK_THAT(message("point = 3\n"), Catch::Contains("[[lighting.point]]"));
  CHECK_THAT(message("window = \"none\"\n"), Catch::Contains("[[lighting.point]] lights"));
  const std::string point = "[[lighting.point]]\nposition = [1, 2, 3]\n";
  CHECK_THAT(message(point + "[transport]\nbounces = 1\n"), Catch::Contains("direct light only"));
  CHECK_THAT(message(point + "[material]\nbrdf = \"phong\"\ndiffuse = [1, 0.5, 0.5]\n"),
             Catch::Contains("grey coefficients"));
}
