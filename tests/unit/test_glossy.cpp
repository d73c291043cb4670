#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <cstdio>
#include <random>

#include "../common/scenes.hpp"
#include "prt/basis.hpp"
#include "prt/brdf.hpp"
#include "prt/glossy.hpp"
#include "prt/hemisphere.hpp"
#include "prt/pipeline.hpp"
#include "prt/progress.hpp"
#include "prt/registry.hpp"
#include "prt/relight.hpp"
#include "prt/sh.hpp"
#include "prt/transport.hpp"

using namespace prt;

namespace {

Brdf model(const std::string& name) {
  Brdf b;
  b.model = brdf_model(name);
  b.kd = 0.3;
  b.ks = name == "lambert" ? 0.0 : 0.7;
  b.exponent = 8;
  b.alpha_x = 0.25, b.alpha_y = 0.5;
  b.roughness = 0.4;
  b.f0 = 0.3;
  return b;
}

Eigen::Vector3d uniform_upper(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const double z = u(rng), phi = 2 * M_PI * u(rng), r = std::sqrt(1 - z * z);
  return {r * std::cos(phi), r * std::sin(phi), z};
}

// One vertex per normal, every direction above its tangent plane visible.
struct OpenVertices {
  Mesh mesh;
  VisibilityBits visibility;
};
OpenVertices open_vertices(const std::vector<Eigen::Vector3f>& normals, const DirectionSet& set) {
  OpenVertices out;
  for (const auto& n : normals) {
    out.mesh.positions.push_back(Eigen::Vector3f::Zero());
    out.mesh.normals.push_back(n.normalized());
  }
  out.visibility = VisibilityBits(normals.size(), set.size());
  for (std::size_t v = 0; v < normals.size(); ++v)
    for (Eigen::Index k = 0; k < set.size(); ++k)
      if (out.mesh.normals[v].cast<double>().dot(set.directions.row(k)) > 0)
        out.visibility.set(v, k);
  return out;
}

// A smooth light in order-5 SH: a broad lobe toward `d` plus sky.
Eigen::MatrixX3d smooth_light(const Eigen::Vector3d& d) {
  const DirectionSet q = hemisphere::upper_quadrature(1);  // unused; keeps includes honest
  (void)q;
  const Eigen::VectorXd lobe = sh::clamped_cosine(5, d.normalized());
  Eigen::MatrixX3d l(25, 3);
  for (int c = 0; c < 3; ++c) l.col(c) = (1.0 + 0.5 * c) * lobe;
  l(0, 0) += 0.5 * 2 * std::sqrt(M_PI);
  return l;
}

// The "hsh" plug-in as exit basis.
std::shared_ptr<Basis> hsh(PluginRegistry& registry, int order, bool reduced,
                           bool least_squares = true) {
  Params params;
  params.set("order", std::int64_t(order));
  params.set("reduced", reduced);
  params.set("projection", std::string(least_squares ? "least-squares" : "zero"));
  return registry.create<Basis>("hsh", params);
}

std::shared_ptr<Basis> sh_basis(PluginRegistry& registry, int order) {
  Params params;
  params.set("order", std::int64_t(order));
  return registry.create<Basis>("sh", params);
}

// Exit basis values at one local direction.
Eigen::RowVectorXd exit_at(const Basis& exit, const Eigen::Vector3d& v) {
  return exit.evaluate(v.transpose()).row(0);
}

// Exact exit radiance toward local view `v` at a vertex with frame F for the
// band-limited light l (order-5 SH, channel 0): int_H L(s) rho(v, s) s_z ds.
double exact_exit(const Brdf& brdf, const Frame& frame, const Eigen::VectorXd& l,
                  const Eigen::Vector3d& v, const DirectionSet& dense) {
  double sum = 0, y[25];
  for (Eigen::Index k = 0; k < dense.size(); ++k) {
    const Eigen::Vector3d s = dense.directions.row(k).transpose();
    const Eigen::Vector3d local = frame * s;
    if (local.z() <= 0) continue;
    sh::evaluate(5, s.x(), s.y(), s.z(), y);
    const double radiance = Eigen::Map<const Eigen::VectorXd>(y, 25).dot(l);
    sum += dense.weights[k] * radiance * brdf.evaluate(local, v) * local.z();
  }
  return sum;
}

}  // namespace

TEST_CASE("BRDFs are reciprocal, zero below the horizon and conserve energy", "[glossy]") {
  std::mt19937_64 rng(3);
  for (const char* name : {"lambert", "phong", "ward", "cook-torrance"}) {
    const Brdf b = model(name);
    for (int i = 0; i < 50; ++i) {
      const Eigen::Vector3d a = uniform_upper(rng), c = uniform_upper(rng);
      CHECK(b.evaluate(a, c) == Approx(b.evaluate(c, a)).epsilon(1e-9));
      CHECK(b.evaluate(a, Eigen::Vector3d(c.x(), c.y(), -c.z())) == 0.0);
      CHECK(b.evaluate(a, c) >= 0.0);
    }
    // Directional albedo int rho cos <= kd + ks = 1 (Monte Carlo, 4 sigma slack).
    const DirectionSet h = hemisphere::upper_quadrature(96);
    for (double z : {0.95, 0.6}) {
      const Eigen::Vector3d in(std::sqrt(1 - z * z), 0, z);
      double albedo = 0;
      for (Eigen::Index k = 0; k < h.size(); ++k)
        albedo +=
            h.weights[k] * b.evaluate(in, h.directions.row(k).transpose()) * h.directions(k, 2);
      INFO(name << " at cos " << z);
      CHECK(albedo <= 1.02);
      CHECK(albedo > 0.25);
    }
  }
}

TEST_CASE("BRDF matrices agree with Monte Carlo integration of the BRDF", "[glossy]") {
  std::vector<int> all(16);
  for (int i = 0; i < 16; ++i) all[i] = i;
  std::mt19937_64 rng(11);
  for (const char* name : {"lambert", "phong", "ward", "cook-torrance"}) {
    const Brdf b = model(name);
    const Eigen::MatrixXd matrix = brdf_matrix(b, 4, all, 3);
    REQUIRE(matrix.rows() == 16);
    REQUIRE(matrix.cols() == 9);
    // Uniform samples over H x H: pdf 1 / (2 pi)^2.
    const int n = 400000;
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(16, 9), sum2 = sum;
    double yv[16], ys[9];
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d v = uniform_upper(rng), s = uniform_upper(rng);
      sh::evaluate(4, v.x(), v.y(), v.z(), yv);
      sh::evaluate(3, s.x(), s.y(), s.z(), ys);
      const double f = b.evaluate(s, v) * s.z() * 4 * M_PI * M_PI;
      for (int r = 0; r < 16; ++r)
        for (int c = 0; c < 9; ++c) {
          const double x = yv[r] * ys[c] * f;
          sum(r, c) += x, sum2(r, c) += x * x;
        }
    }
    const Eigen::MatrixXd mean = sum / n;
    const Eigen::MatrixXd sigma = ((sum2 / n - mean.cwiseProduct(mean)) / n).cwiseSqrt();
    INFO(name);
    for (int r = 0; r < 16; ++r)
      for (int c = 0; c < 9; ++c) {
        INFO("B(" << r << ", " << c << ") = " << matrix(r, c) << ", Monte Carlo " << mean(r, c)
                  << " +- " << sigma(r, c));
        CHECK(std::abs(matrix(r, c) - mean(r, c)) < 5 * sigma(r, c) + 2e-3);
      }
  }
}

TEST_CASE("glossy transfer reproduces the exit radiance of an open vertex", "[glossy]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  auto basis = sh_basis(registry, 5);
  const DirectionSet set = DirectionSet::make("fibonacci", 20000, 1);
  const OpenVertices open = open_vertices({{0, 0, 1}, {0.3f, 0.8f, -0.2f}, {-1, 0.1f, 0.2f}}, set);
  const std::vector<Frame> frames = tangent_frames(open.mesh);
  const Eigen::MatrixX3d light = smooth_light({0.2, 1, 0.4});
  std::mt19937_64 rng(5);
  for (const char* name : {"lambert", "phong", "ward", "cook-torrance"}) {
    const Brdf brdf = model(name);
    double error[2] = {0, 0}, energy = 0;
    for (const bool least_squares : {true, false}) {
      const auto exit = hsh(registry, 5, false, least_squares);
      const GlossyOperator glossy = GlossyOperator::make(brdf, *exit, 5, least_squares, 1e-10);
      const TransferSignal t = glossy_transfer(open.mesh, set, open.visibility, *basis, glossy,
                                               frames, GlossyMethod::rotate_sh, nullptr);
      REQUIRE(t.coefficients.cols() == 25 * 25);
      for (std::size_t p = 0; p < open.mesh.vertex_count(); ++p) {
        const Eigen::MatrixXd m =
            Eigen::Map<const MatrixXfRow>(t.coefficients.row(p).data(), 25, 25).cast<double>();
        const Eigen::VectorXd e = m * light.col(0);
        for (int i = 0; i < 20; ++i) {
          const Eigen::Vector3d v = uniform_upper(rng);
          const double approx = exit_at(*exit, v).dot(e);
          const double exact = exact_exit(brdf, frames[p], light.col(0), v, set);
          error[least_squares] += (approx - exact) * (approx - exact);
          if (least_squares) energy += exact * exact;
        }
      }
    }
    INFO(name << ": least-squares error " << std::sqrt(error[1] / energy) << ", zero-hemisphere "
              << std::sqrt(error[0] / energy));
    CHECK(error[1] < error[0]);
    if (std::string(name) == "lambert") CHECK(std::sqrt(error[1] / energy) < 1e-3);
    CHECK(std::sqrt(error[1] / energy) < 0.1);
  }
}

TEST_CASE("white furnace: a Lambertian sphere of albedo 1 under light 1 returns 1", "[glossy]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  auto basis = sh_basis(registry, 5);
  const Mesh sphere = make_sphere(2);
  const DirectionSet set = DirectionSet::make("fibonacci", 4096, 1);
  TransportOptions options;
  options.keep_visibility = true;
  const TransportResult traced =
      diffuse_transfer(sphere, set, Eigen::MatrixXd(set.size(), 0), options, nullptr);
  Brdf white;  // lambert, kd = 1
  const auto exit = hsh(registry, 5, true);
  const GlossyOperator glossy = GlossyOperator::make(white, *exit, 5, true, 1e-10);
  const std::vector<Frame> frames = tangent_frames(sphere);
  const TransferSignal t = glossy_transfer(sphere, set, traced.visibility, *basis, glossy, frames,
                                           GlossyMethod::rotate_sh, nullptr);
  Eigen::MatrixX3d light = Eigen::MatrixX3d::Zero(25, 3);
  light.row(0).setConstant(2 * std::sqrt(M_PI));  // L = 1 everywhere
  const MatrixXfRow values =
      exit_values(*exit, local_view_directions(sphere, frames, {0.3f, 4.f, 2.f}));
  const Eigen::MatrixX3f radiance = relight(exact_form(t), light, &values);
  CHECK((radiance.array() - 1.f).abs().maxCoeff() < 2e-3f);
}

TEST_CASE("glossy Lambert transfer agrees with diffuse transfer under shadowing", "[glossy]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  auto basis = sh_basis(registry, 5);
  const Mesh scene = test::sphere_over_plane();
  const DirectionSet set = DirectionSet::make("fibonacci", 4096, 1);
  TransportOptions options;
  options.keep_visibility = true;
  const TransportResult traced =
      diffuse_transfer(scene, set, Eigen::MatrixXd(set.size(), 0), options, nullptr);
  const TransferSignal diffuse = project_visibility(scene, set, traced.visibility, *basis);
  const Eigen::MatrixX3d light = smooth_light({0.2, 1, 0.4});
  const Eigen::VectorXd expected = diffuse.coefficients.cast<double>() * light.col(0);
  Brdf white;
  double errors[2];
  for (const bool least_squares : {true, false}) {
    // The reduced basis exists for least squares only.
    const auto exit = hsh(registry, 5, least_squares, least_squares);
    const GlossyOperator glossy = GlossyOperator::make(white, *exit, 5, least_squares, 1e-10);
    const TransferSignal t =
        glossy_transfer(scene, set, traced.visibility, *basis, glossy, tangent_frames(scene),
                        GlossyMethod::rotate_sh, nullptr);
    double error = 0;
    for (Eigen::Index p = 0; p < t.vertices(); ++p) {
      const Eigen::MatrixXd m =
          Eigen::Map<const MatrixXfRow>(t.coefficients.row(p).data(), exit->size(), 25)
              .cast<double>();
      const double radiance =
          exit_at(*exit, Eigen::Vector3d(0.3, 0.2, 0.9).normalized()) * m * light.col(0);
      error += (radiance - expected[p]) * (radiance - expected[p]);
    }
    errors[least_squares] = std::sqrt(error / expected.squaredNorm());
  }
  INFO("relative RMS: least squares " << errors[1] << ", zero hemisphere " << errors[0]);
  CHECK(errors[1] < 0.05);
  CHECK(errors[1] < 0.5 * errors[0]);  // the point of Sloan 2003 §3.2
}

namespace {

const char* kGlossyBox = R"(
[mesh]
generate = "open-box"
detail = 1
[material]
albedo = [1, 1, 1]
brdf = "%s"
diffuse = 0.2
specular = 0.8
exponent = 20
[transport]
rays = 1024
[basis]
plugin = "sh"
order = 5
[exit]
plugin = "hsh"
reduced = true
[lighting]
constant = [1, 1, 1]
[camera]
width = 64
height = 48
position = [%g, 2.5, 1.0]
target = [0, -0.5, 0]
[ground_truth]
samples = 1024
)";

SceneSpec glossy_box(PluginRegistry& registry, const std::string& brdf, double camera_x) {
  char text[1024];
  std::snprintf(text, sizeof text, kGlossyBox, brdf.c_str(), camera_x);
  return SceneSpec::parse(text, "glossy_box.toml", registry);
}

}  // namespace

TEST_CASE("glossy radiance follows the camera, and Lambertian radiance does not", "[glossy]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Progress::set_enabled(false);
  for (const char* brdf : {"phong", "lambert"}) {
    StageTimes times;
    const SceneSpec left = glossy_box(registry, brdf, -1.5),
                    right = glossy_box(registry, brdf, 1.5);
    const BakeData data = bake(left, registry, {true}, times);
    CHECK(data.transfer.kind == (std::string(brdf) == "phong" ? "glossy" : "diffuse"));
    const Rendered a = render(left, data, registry, times);
    const Rendered b = render(right, data, registry, times);
    const double change = (a.vertex_radiance - b.vertex_radiance).cwiseAbs().maxCoeff();
    INFO(brdf << ": largest change of a vertex's radiance " << change);
    if (std::string(brdf) == "phong") {
      CHECK(change > 0.1);
      // ...and the ground truth, an independent computation, agrees.
      const Rendered truth = render_ground_truth(right, data.mesh, registry, {true}, times);
      const ErrorStats e = vertex_error(b.vertex_radiance, truth.vertex_radiance);
      INFO("relative RMS against the ground truth " << e.relative_rms);
      CHECK(e.relative_rms < 0.12);
      CHECK(mean_absolute_difference(a.image, b.image) > 0);
    } else {
      CHECK(change < 1e-6);
    }
  }
  Progress::set_enabled(true);
}

TEST_CASE("a bake made with another projection or material is refused", "[glossy]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Progress::set_enabled(false);
  StageTimes times;
  const SceneSpec scene = glossy_box(registry, "phong", 1.0);
  const BakeData data = bake(scene, registry, {true}, times);
  char text[1024];
  std::snprintf(text, sizeof text, kGlossyBox, "phong", 1.0);
  std::string changed = text;
  changed.replace(changed.find("exponent = 20"), 13, "exponent = 20\nprojection = \"zero\"");
  CHECK_THROWS_WITH(render(SceneSpec::parse(changed, "zero.toml", registry), data, registry, times),
                    Catch::Contains("bake again"));
  CHECK_THROWS_WITH(render(glossy_box(registry, "cook-torrance", 1.0), data, registry, times),
                    Catch::Contains("bake again"));
  std::string other_exit = text;
  other_exit.replace(other_exit.find("reduced = true"), 14, "reduced = false");
  CHECK_THROWS_WITH(
      render(SceneSpec::parse(other_exit, "exit.toml", registry), data, registry, times),
      Catch::Contains("exit basis \"hsh\"") && Catch::Contains("bake again"));
  CHECK_NOTHROW(render(glossy_box(registry, "phong", -1.0), data, registry, times));
  Progress::set_enabled(true);
}
