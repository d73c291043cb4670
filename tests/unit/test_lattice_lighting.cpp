#include <Eigen/Geometry>
#include <catch2/catch.hpp>

#include "prt/compressor.hpp"
#include "prt/lattice_lighting.hpp"
#include "prt/point_lights.hpp"
#include "prt/registry.hpp"
#include "prt/sh.hpp"

using namespace prt;

namespace {
class LatticeSH : public Basis {
 public:
  int size() const override { return 9; }
  bool orthonormal() const override { return true; }
  Eigen::MatrixXd evaluate(const Directions& d) const override { return sh::evaluate(3, d); }
};

Environment smooth_map() {
  std::vector<float> rgb;
  const int w = 256, h = 128;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const Eigen::Vector3d d = equirect_direction((x + 0.5) / w, (y + 0.5) / h);
      const float v = float(1.0 + 0.6 * d.x() + 0.3 * d.y() * d.z());
      rgb.insert(rgb.end(), {v, 0.5f * v, 2.f * v});
    }
  return Environment::from_pixels(w, h, rgb);
}
}  // namespace

TEST_CASE("rotating the lattice agrees with brute-force re-sampling", "[lattice][rotation]") {
  const int r = 16;
  const Environment env = smooth_map();
  const Eigen::MatrixX3d canonical = lattice_lighting(env, r);
  const DirectionSet lattice = DirectionSet::cubemap(r);
  CHECK((rotate_lattice_lighting(canonical, r, Eigen::Matrix3d::Identity()) - canonical)
            .cwiseAbs()
            .maxCoeff() < 1e-12);
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(0.9, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix();
  const LatticeSH basis;
  const Eigen::MatrixX3d by_lattice =
      basis.project(rotate_lattice_lighting(canonical, r, rotation).transpose(), lattice)
          .transpose();
  Environment rotated = env;
  rotated.set_rotation(rotation);
  const Eigen::MatrixX3d brute = rotated.project(basis);  // re-samples the whole map
  CHECK((by_lattice - brute).norm() < 0.01 * brute.norm());
}

TEST_CASE("a point light shades with the transport at the nearest lattice direction",
          "[lattice][point-light]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Params p;
  p.set("resolution", std::int64_t(8));
  auto haar = registry.create<Basis>("haar", p);
  const Mesh sphere = make_sphere(2);
  const DirectionSet lattice = DirectionSet::cubemap(8);
  // Unshadowed convex sphere: T(w) = max(n.w, 0) / pi exactly, kept whole.
  TransferSignal t;
  Eigen::MatrixXd samples(sphere.vertex_count(), lattice.size());
  for (std::size_t v = 0; v < sphere.vertex_count(); ++v)
    for (Eigen::Index k = 0; k < lattice.size(); ++k)
      samples(v, k) =
          std::max(0.0, sphere.normals[v].cast<double>().dot(lattice.directions.row(k))) / M_PI;
  t.coefficients = haar->project(samples, lattice).cast<float>();
  Params none;
  auto exact = registry.create<Compressor>("none", none)->encode(t, nullptr);
  PointLight light;
  light.position = Eigen::Vector3d(0, 50, 0);
  light.intensity = 2;
  const PointLightProjector projector(*haar, 1);
  REQUIRE(projector.rule() == PointLightProjector::Rule::nearest);
  const Eigen::MatrixX3f e = point_light_radiance(sphere, exact, 1, projector, {light});
  for (std::size_t v = 0; v < sphere.vertex_count(); ++v) {
    const Eigen::Vector3d toward =
        (light.position - sphere.positions[v].cast<double>()).normalized();
    const int k = cubemap_texel(toward, 8);
    CHECK(e(v, 0) == Approx(2 * samples(v, k)).margin(1e-5));
  }
}
