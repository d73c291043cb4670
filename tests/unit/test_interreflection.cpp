#include <catch2/catch.hpp>
#include <cstdint>
#include <filesystem>
#include <stdexcept>

#include "prt/bounce_passes.hpp"
#include "prt/checkpoint.hpp"
#include "prt/environment.hpp"
#include "prt/ground_truth.hpp"
#include "prt/interreflection.hpp"
#include "prt/sh.hpp"
#include "prt/subsurface.hpp"
#include "prt/transport.hpp"

using namespace prt;
namespace fs = std::filesystem;

namespace {

// Order-4 SH transfer of a scene plus the hits of its shadow rays.
TransportResult traced(const Mesh& mesh, int rays) {
  const DirectionSet set = DirectionSet::make("fibonacci", rays, 1);
  TransportOptions options;
  options.keep_hits = true;
  return diffuse_transfer(mesh, set, set.weights.asDiagonal() * sh::evaluate(4, set.directions),
                          options, nullptr);
}

// Exit radiance (albedo excluded) under constant light 1.
Eigen::VectorXd under_constant_light(const MatrixXfRow& transfer) {
  Eigen::VectorXd l = Eigen::VectorXd::Zero(transfer.cols());
  l[0] = 2 * std::sqrt(M_PI);
  return transfer.cast<double>() * l;
}

bool near_corner(const Eigen::Vector3f& p) {
  int at_wall = 0;
  for (int c : {0, 2}) at_wall += std::abs(p[c]) > 0.8f;
  return at_wall == 2 && p.y() < -0.8f;  // floor corners: three walls meet
}

}  // namespace

TEST_CASE("white furnace: a convex sphere returns the light, with or without bounces",
          "[interreflection]") {
  const Mesh sphere = make_sphere(2);
  const TransportResult t = traced(sphere, 2048);
  const DirectionSet set = DirectionSet::make("fibonacci", 2048, 1);
  for (const auto& hits : t.hits) CHECK(hits.empty());  // nothing to hit on a convex object
  for (int bounces : {0, 3}) {
    const BouncedTransfer r = bounce_passes(t.transfer.coefficients, bounces,
                                            diffuse_bounce(sphere, set, t.hits, 1.0), nullptr);
    const Eigen::VectorXd radiance = under_constant_light(r.total);
    CHECK((radiance.array() - 1.0).abs().maxCoeff() < 0.01);
  }
}

TEST_CASE("inter-reflection brightens an open box's corners, converges and adds no energy",
          "[interreflection]") {
  const Mesh box = make_open_box(12);
  const int rays = 2048;
  const TransportResult t = traced(box, rays);
  const DirectionSet set = DirectionSet::make("fibonacci", rays, 1);
  const double albedo = 0.8;
  const BouncedTransfer r =
      bounce_passes(t.transfer.coefficients, 4, diffuse_bounce(box, set, t.hits, albedo), nullptr);
  REQUIRE(r.bounce_norms.size() == 4);
  for (std::size_t b = 1; b < r.bounce_norms.size(); ++b) {
    CHECK(r.bounce_norms[b] < r.bounce_norms[b - 1]);  // converges
    CHECK(r.bounce_norms[b] <= albedo * r.bounce_norms[b - 1] * 1.02);
  }
  const Eigen::VectorXd direct = under_constant_light(t.transfer.coefficients);
  const Eigen::VectorXd total = under_constant_light(r.total);
  // A white furnace with albedo < 1 never reflects more than it receives.
  CHECK((albedo * total).maxCoeff() <= 1.0 + 1e-3);
  CHECK((total - direct).minCoeff() > -1e-4);
  double corner_gain = 0, corner_direct = 0;
  for (std::size_t v = 0; v < box.vertex_count(); ++v)
    if (near_corner(box.positions[v])) {
      corner_gain += total[v] - direct[v];
      corner_direct += direct[v];
    }
  REQUIRE(corner_direct > 0);
  CHECK(corner_gain / corner_direct > 0.3);  // corners see mostly walls
}

TEST_CASE("two bounces match the ground truth's independent bounces", "[interreflection]") {
  const Mesh box = make_open_box(8);
  const int rays = 4096;
  const TransportResult t = traced(box, rays);
  const DirectionSet set = DirectionSet::make("fibonacci", rays, 1);
  const BouncedTransfer r =
      bounce_passes(t.transfer.coefficients, 2, diffuse_bounce(box, set, t.hits, 0.7), nullptr);
  const Eigen::VectorXd prt_radiance = under_constant_light(r.total);
  const Environment light = Environment::constant(Eigen::Vector3f::Ones());
  const Eigen::MatrixX3f direct = ground_truth_radiance(box, light, 1024, 3, nullptr);
  const Eigen::MatrixX3f truth = ground_truth_bounces(box, direct, 2, 0.7, 1024, 3, nullptr);
  const Eigen::VectorXd reference = truth.col(0).cast<double>();
  const double relative = (prt_radiance - reference).norm() / reference.norm();
  INFO("relative RMS " << relative);
  CHECK(relative < 0.03);
  // Without the bounces the transfer is measurably darker than the truth.
  CHECK((under_constant_light(t.transfer.coefficients) - reference).norm() / reference.norm() >
        5 * relative);
}

TEST_CASE("subsurface: a lit plane reflects the dipole's total diffuse reflectance",
          "[subsurface]") {
  SubsurfaceMaterial m;
  m.sigma_a = 0.01, m.sigma_s = 0.1, m.eta = 1.3;
  m.mm_per_unit = 250;  // a 2-unit plane is 500 mm wide; mean free path ~9 mm
  const Mesh plane = make_plane(160);
  MatrixXfRow irradiance = MatrixXfRow::Ones(plane.vertex_count(), 2);
  irradiance.col(1) *= 3;
  const MatrixXfRow s = subsurface_transfer(plane, irradiance, m);
  // The centre vertex sees the whole (effectively infinite) plane.
  std::size_t centre = 0;
  for (std::size_t v = 0; v < plane.vertex_count(); ++v)
    if (plane.positions[v].norm() < plane.positions[centre].norm()) centre = v;
  const double f_dt = 1 - diffuse_fresnel_reflectance(m.eta);
  const double expected = f_dt * f_dt * dipole_total_reflectance(m);
  INFO("expected " << expected << ", got " << s(centre, 0));
  CHECK(s(centre, 0) == Approx(expected).epsilon(0.05));
  CHECK(s(centre, 1) == Approx(3 * s(centre, 0)).epsilon(1e-5));  // linear in the transfer
  CHECK(expected < 1.0);
  // The hierarchy agrees with the direct sum (error 0 opens every group).
  SubsurfaceMaterial exact = m;
  exact.error = 0;
  const Mesh small = make_plane(24);
  const MatrixXfRow ones = MatrixXfRow::Ones(small.vertex_count(), 1);
  const MatrixXfRow fast = subsurface_transfer(small, ones, m);
  const MatrixXfRow direct = subsurface_transfer(small, ones, exact);
  CHECK((fast - direct).norm() / direct.norm() < 0.02);
  // More absorption, less light.
  SubsurfaceMaterial absorbing = m;
  absorbing.sigma_a = 0.05;
  CHECK(dipole_total_reflectance(absorbing) < dipole_total_reflectance(m));
  CHECK(std::isfinite(dipole_profile(m, 0.0)));
}

TEST_CASE(
    "subsurface ground truth: the direct pair sum matches the plane's total reflectance "
    "and the transfer's hierarchy",
    "[subsurface][ground-truth]") {
  SubsurfaceMaterial m;
  m.sigma_a = 0.01, m.sigma_s = 0.1, m.eta = 1.3;
  m.mm_per_unit = 250;
  const Mesh plane = make_plane(120);
  Eigen::MatrixX3f irradiance = Eigen::MatrixX3f::Ones(plane.vertex_count(), 3);
  irradiance.col(2) *= 0.5f;
  const Eigen::MatrixX3f s = subsurface_direct(plane, irradiance, m);
  std::size_t centre = 0;
  for (std::size_t v = 0; v < plane.vertex_count(); ++v)
    if (plane.positions[v].norm() < plane.positions[centre].norm()) centre = v;
  const double f_dt = 1 - diffuse_fresnel_reflectance(m.eta);
  CHECK(s(centre, 0) == Approx(f_dt * f_dt * dipole_total_reflectance(m)).epsilon(0.05));
  CHECK(s(centre, 2) == Approx(0.5 * s(centre, 0)).epsilon(1e-5));
  CHECK(s.allFinite());
  // The bake's hierarchy with every group opened is the same sum.
  SubsurfaceMaterial exact = m;
  exact.error = 0;
  const Mesh sphere = make_sphere(3);
  MatrixXfRow lit(sphere.vertex_count(), 1);
  Eigen::MatrixX3f lit3(sphere.vertex_count(), 3);
  for (std::size_t v = 0; v < sphere.vertex_count(); ++v)
    lit(v, 0) = lit3(v, 0) = lit3(v, 1) = lit3(v, 2) = std::max(0.f, sphere.normals[v].y());
  const MatrixXfRow hierarchy = subsurface_transfer(sphere, lit, exact);
  const Eigen::MatrixX3f direct = subsurface_direct(sphere, lit3, exact);
  CHECK((hierarchy.col(0) - direct.col(0)).norm() / direct.col(0).norm() < 1e-4);
  CHECK(direct.col(0).minCoeff() > 0);  // light reaches the unlit side
}

TEST_CASE("bounces and subsurface gathered a slab of vertices at a time equal the whole",
          "[interreflection][checkpoint]") {
  const Mesh box = make_open_box(8);
  const TransportResult t = traced(box, 512);
  const DirectionSet set = DirectionSet::make("fibonacci", 512, 1);
  const MatrixXfRow& direct = t.transfer.coefficients;
  const MatrixXfRow whole = gather_bounce(box, set, t.hits, direct, 0.8);
  const std::size_t v = box.vertex_count(), cut = v / 3;
  REQUIRE(cut > 10);
  CHECK(gather_bounce(box, set, t.hits, direct, 0.8, cut, v) == whole.bottomRows(v - cut));
  CHECK(gather_bounce(box, set, t.hits, direct, 0.8, 0, cut) == whole.topRows(cut));
  CHECK(gather_bounce(box, set, t.hits, direct, 0.8, cut, cut).rows() == 0);
  const SubsurfaceMaterial marble;
  const MatrixXfRow scattered = subsurface_transfer(box, direct, marble);
  const SubsurfaceScattering parts(box, direct, marble);
  CHECK(parts.rows(cut, v) == scattered.bottomRows(v - cut));
  CHECK(parts.rows(0, cut) == scattered.topRows(cut));
  CHECK_THROWS_WITH(parts.rows(cut, v + 1), Catch::Contains("vertices"));
}

TEST_CASE("bounces kept in a checkpoint resume after a kill to the same transfer",
          "[interreflection][checkpoint]") {
  const fs::path output = fs::temp_directory_path() / "prt_bounces" / "bake.h5";
  fs::remove_all(output.parent_path());
  fs::create_directories(output.parent_path());
  const CheckpointStore store(output, "key", "test");
  const MatrixXfRow direct = MatrixXfRow::Random(50, 3);
  // A bounce that halves the light and mixes neighbouring rows, counting the
  // rows it gathers; "killed" (throws) once it has gathered `limit` rows.
  std::size_t gathered = 0, limit = SIZE_MAX;
  const BounceFunction bounce = [&](const MatrixXfRow& previous, std::size_t first,
                                    std::size_t last) {
    if (gathered + (last - first) > limit) throw std::runtime_error("killed");
    gathered += last - first;
    MatrixXfRow out(Eigen::Index(last - first), previous.cols());
    for (std::size_t p = first; p < last; ++p)
      out.row(Eigen::Index(p - first)) =
          0.25f * (previous.row(Eigen::Index(p)) + previous.row(Eigen::Index((p + 7) % 50)));
    return out;
  };
  const BouncedTransfer reference = bounce_passes(direct, 3, bounce, nullptr);
  REQUIRE(gathered == 150);
  std::vector<std::string> said;
  BounceCheckpoint checkpoint{&store, "channel-2.",
                              [&](const std::string& text) { said.push_back(text); }, 20};
  // Killed inside bounce 2 after its first slab (20 rows), then again inside
  // bounce 3; each rerun gathers only what was not kept.
  gathered = 0, limit = 50 + 20 + 5;
  CHECK_THROWS_WITH(bounce_passes(direct, 3, bounce, nullptr, checkpoint), "killed");
  CHECK(store.has("channel-2.bounce-1"));
  CHECK(store.has("channel-2.bounce-2.rows-000000000000-000000000020"));
  gathered = 0, limit = 30 + 45;
  CHECK_THROWS_WITH(bounce_passes(direct, 3, bounce, nullptr, checkpoint), "killed");
  CHECK(gathered == 30 + 40);  // bounce 2's last 30 rows, bounce 3's first two slabs
  CHECK_FALSE(store.has("channel-2.bounce-1"));  // superseded by bounce 2's state
  gathered = 0, limit = SIZE_MAX;
  const BouncedTransfer resumed = bounce_passes(direct, 3, bounce, nullptr, checkpoint);
  CHECK(gathered == 10);
  CHECK(resumed.total == reference.total);
  CHECK(resumed.bounce_norms == reference.bounce_norms);
  REQUIRE(said.size() >= 3);
  CHECK(said[0] == "resuming: inter-reflection (channel-2) after bounce 1 of 3");
  CHECK_THAT(said[1], Catch::StartsWith("resuming: 1 of 3 slabs of bounce 2 kept in"));
  // A kept state that does not fit this transfer is refused with a message.
  store.save("channel-2.bounce-3.total", MatrixXfRow(MatrixXfRow::Zero(4, 3)));
  CHECK_THROWS_WITH(bounce_passes(direct, 3, bounce, nullptr, checkpoint),
                    Catch::Contains("does not match the transfer") && Catch::Contains("--restart"));
  store.remove();
}
