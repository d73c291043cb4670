// Probes: the grid, the probe transfer, shading from probes with and without
// the leak control, probe scenes and their bake files.
#include <H5Cpp.h>
#include <tbb/global_control.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "../../framework/src/bake_userblock.hpp"
#include "prt/bake.hpp"
#include "prt/checkpoint.hpp"
#include "prt/mesh_compose.hpp"
#include "prt/probe_render.hpp"
#include "prt/probe_shading.hpp"
#include "prt/probe_transfer.hpp"
#include "prt/receivers.hpp"
#include "prt/sh.hpp"
#include "prt/visible_products.hpp"

using namespace prt;
namespace fs = std::filesystem;

namespace {

PluginRegistry& registry() {
  static PluginRegistry r({PRT_BUILD_PLUGIN_DIR});
  return r;
}

std::shared_ptr<Basis> sh_basis(int order) {
  Params params;
  params.set("order", std::int64_t(order));
  return registry().create<Basis>("sh", params, SourceLocation{"test"});
}

// A closed slab x in [lo, hi], wide in y and z: a wall.
Mesh wall(float lo, float hi) {
  Mesh box = make_box(1.0f);
  for (Eigen::Vector3f& p : box.positions) {
    p.x() = p.x() > 0 ? hi : lo;
    p.y() *= 20, p.z() *= 20;
  }
  return box;
}

}  // namespace

TEST_CASE("a probe grid is centred in its box and interpolates linear functions exactly",
          "[probes]") {
  const ProbeGrid grid = probe_grid_over({-1, 0, -2}, {1, 1, 2}, 0.5f);
  CHECK(grid.counts == std::array<int, 3>{4, 2, 8});
  // Centred: as far from the low face as from the high one, none on a face.
  CHECK(grid.origin.x() == Approx(-0.75));
  CHECK(grid.position(grid.count() - 1).x() == Approx(0.75));
  CHECK(grid.origin.y() == Approx(0.25));
  auto linear = [](const Eigen::Vector3f& p) { return 2 * p.x() - 3 * p.y() + 0.5f * p.z() + 1; };
  for (const Eigen::Vector3f point :
       {Eigen::Vector3f(0.1f, 0.4f, -0.3f), Eigen::Vector3f(-0.7f, 0.26f, 1.6f),
        Eigen::Vector3f(0.75f, 0.75f, 1.75f)}) {
    std::array<std::uint32_t, 8> probes;
    std::array<float, 8> weights;
    grid.cell(point, probes, weights);
    float sum = 0, value = 0;
    for (int c = 0; c < 8; ++c) {
      sum += weights[c];
      value += weights[c] * linear(grid.position(probes[c]));
    }
    CHECK(sum == Approx(1).epsilon(1e-6));
    CHECK(value == Approx(linear(point)).epsilon(1e-5));
  }
  // Outside the grid, or NaN: clamped to the grid, weights still sum to 1.
  for (const Eigen::Vector3f point :
       {Eigen::Vector3f(100, -100, 0), Eigen::Vector3f(NAN, 0, INFINITY)}) {
    std::array<std::uint32_t, 8> probes;
    std::array<float, 8> weights;
    grid.cell(point, probes, weights);
    float sum = 0;
    for (int c = 0; c < 8; ++c) {
      CHECK(probes[c] < grid.count());
      sum += weights[c];
    }
    CHECK(sum == Approx(1));
  }
  // A flat box gets one probe along that axis.
  CHECK(probe_grid_over({0, 0, 0}, {1, 0, 1}, 0.25f).counts[1] == 1);
  CHECK_THROWS_WITH(probe_grid_over({0, 0, 0}, {1, 1, 1}, 0.0f),
                    Catch::Contains("not a positive number"));
  CHECK_THROWS_WITH(probe_grid_over({0, 0, 0}, {1e4f, 1, 1}, 0.1f),
                    Catch::Contains("at most 4096"));
}

TEST_CASE("probe transfer: identity in open air, a hemisphere over a floor, zero inside",
          "[probes]") {
  const auto basis = sh_basis(3);
  const DirectionSet set = DirectionSet::fibonacci(4096);
  // A large floor below y = 0 (a closed slab), a probe above it, one inside it,
  // one far off to the side (open air: only the floor's far edge is seen).
  Mesh floor = make_box(1.0f);
  // So wide that the probe's horizon is within 1e-4 radians of the equator.
  for (Eigen::Vector3f& p : floor.positions)
    p = Eigen::Vector3f(1e4f * p.x(), p.y() - 0.5f, 1e4f * p.z());
  ProbeGrid grid;
  grid.origin = {0, -0.5f, 0};
  grid.spacing = 1;
  grid.counts = {1, 2, 1};  // (0, -0.5, 0) inside the slab, (0, 0.5, 0) above it
  const RayCaster caster(floor);
  const ProbeTransfer t =
      probe_transfer(caster, floor, grid, set, *basis, *basis, 0.25, true, nullptr);
  REQUIRE(t.transfer.vertices() == 2);
  CHECK(t.transfer.kind == "incident");
  CHECK(t.valid[0] == 0);
  CHECK(t.valid[1] == 1);
  CHECK(t.transfer.coefficients.row(0).cwiseAbs().maxCoeff() == 0);
  CHECK(t.rays_cast == 2 * 4096);
  // Under constant unit light (coefficient 0 = sqrt(4 pi)), the probe above the
  // floor receives light over the upper hemisphere: coefficient 0 of that is
  // 2 pi y_0 = sqrt(pi).
  CompressedTransfer exact = exact_form(t.transfer);
  Eigen::MatrixX3d light = Eigen::MatrixX3d::Zero(9, 3);
  light.row(0).setConstant(std::sqrt(4 * M_PI));
  const auto incident = incident_light(exact, 9, light);
  CHECK(incident[1](0, 0) == Approx(std::sqrt(M_PI)).epsilon(2e-3));
  CHECK(incident[0].norm() == 0);
  // The step of light at the horizon, band-limited to l <= 2: 1/2 + 3/4 cos
  // (band 2 of a step is zero), so 1.25 straight up and -0.25 straight down.
  const Eigen::MatrixXd up = basis->evaluate(Directions(Eigen::RowVector3d(0, 1, 0)));
  const Eigen::MatrixXd down = basis->evaluate(Directions(Eigen::RowVector3d(0, -1, 0)));
  CHECK((up * incident[1].col(0))(0) == Approx(1.25).epsilon(2e-3));
  CHECK((down * incident[1].col(0))(0) == Approx(-0.25).epsilon(1e-2));
  // Unshadowed: P^T B, the identity for an orthonormal basis (to quadrature).
  const ProbeTransfer open =
      probe_transfer(caster, floor, grid, set, *basis, *basis, 0.25, false, nullptr);
  const Eigen::Map<const Eigen::Matrix<float, 9, 9, Eigen::RowMajor>> identity(
      open.transfer.coefficients.row(1).data());
  CHECK((identity.cast<double>() - Eigen::MatrixXd::Identity(9, 9)).cwiseAbs().maxCoeff() < 1e-3);
  CHECK(open.rays_cast == 0);
}

TEST_CASE("probe transfer does not depend on the thread count", "[probes]") {
  const auto basis = sh_basis(2);
  const DirectionSet set = DirectionSet::fibonacci(512);
  const Mesh scene = make_room(0);
  const ProbeGrid grid = probe_grid_over(scene.bounds_min(), scene.bounds_max(), 0.5f);
  const RayCaster caster(scene);
  const ProbeTransfer all =
      probe_transfer(caster, scene, grid, set, *basis, *basis, 0.25, true, nullptr);
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const ProbeTransfer single =
      probe_transfer(caster, scene, grid, set, *basis, *basis, 0.25, true, nullptr);
  CHECK(all.valid == single.valid);
  CHECK(all.transfer.coefficients == single.transfer.coefficients);
  // At this spacing the room's ceiling slab holds a layer of probes (y = 2.55).
  const auto invalid = std::count(all.valid.begin(), all.valid.end(), std::uint8_t(0));
  CHECK(invalid > 0);
  CHECK(invalid < std::ptrdiff_t(grid.count()));
}

TEST_CASE("a Lambertian lobe under constant unit light gives exit radiance 1", "[probes]") {
  for (int order : {1, 3, 6}) {
    const auto basis = sh_basis(order);
    std::vector<Eigen::Vector3f> normals{
        {0, 1, 0}, {1, 0, 0}, Eigen::Vector3f(1, -2, 3).normalized()};
    const Eigen::MatrixXd lobes = cosine_lobes(*basis, normals, DirectionSet::fibonacci(2048));
    Eigen::VectorXd constant = Eigen::VectorXd::Zero(basis->size());
    constant[0] = std::sqrt(4 * M_PI);
    for (Eigen::Index v = 0; v < lobes.rows(); ++v)
      CHECK((lobes.row(v) * constant)(0) ==
            Approx(1).epsilon(2e-4));  // the rule's error at the kink
  }
}

TEST_CASE("the leak control keeps light behind a wall out, where plain trilinear lets it in",
          "[probes]") {
  const auto basis = sh_basis(2);
  // Two probes, x = 0 and x = 1, a wall between them at x in [0.4, 0.6].
  const Mesh scene = wall(0.4f, 0.6f);
  const RayCaster caster(scene);
  ProbeGrid grid;
  grid.origin = {0, 0, 0};
  grid.spacing = 1;
  grid.counts = {2, 1, 1};
  std::vector<Eigen::MatrixX3d> incident(2, Eigen::MatrixX3d::Zero(4, 3));  // sh order 2
  incident[0].row(0).setConstant(10 * std::sqrt(4 * M_PI));  // bright side: radiance 10
  incident[1].row(0).setConstant(std::sqrt(4 * M_PI));       // dim side: radiance 1
  Mesh points;  // one point on each side, facing away from the wall
  points.positions = {{0.7f, 0, 0}, {0.3f, 0, 0}};
  points.normals = {{1, 0, 0}, {-1, 0, 0}};
  const Eigen::MatrixXd lobes = cosine_lobes(*basis, points.normals, DirectionSet::fibonacci(2048));
  std::vector<std::uint8_t> valid{1, 1};
  ProbeLookup control;  // visibility, bias 0.25 spacing: the points move to x = 0.95 and 0.05
  const ProbeShading with =
      shade_from_probes(points, grid, valid, incident, lobes, &caster, control);
  ProbeLookup plain;
  plain.interpolation = ProbeInterpolation::trilinear;
  const ProbeShading without =
      shade_from_probes(points, grid, valid, incident, lobes, nullptr, plain);
  CHECK(with.radiance(0, 0) == Approx(1).epsilon(2e-4));   // the dim side's own light
  CHECK(with.radiance(1, 0) == Approx(10).epsilon(2e-4));  // the bright side's
  CHECK(without.radiance(0, 0) == Approx(0.3 * 10 + 0.7 * 1).epsilon(2e-4));  // leaked
  CHECK(with.unseen == 0);
  CHECK(with.rays_cast == 16);
  // An invalid probe drops out; a point that sees no valid probe falls back to
  // the valid ones (counted), one with none around it is black (counted).
  valid = {1, 0};
  const ProbeShading fallback =
      shade_from_probes(points, grid, valid, incident, lobes, &caster, control);
  CHECK(fallback.unseen == 1);
  CHECK(fallback.radiance(0, 0) == Approx(10).epsilon(2e-4));
  valid = {0, 0};
  const ProbeShading none =
      shade_from_probes(points, grid, valid, incident, lobes, &caster, control);
  CHECK(none.no_valid_probe == 2);
  CHECK(none.radiance.cwiseAbs().maxCoeff() == 0);
  CHECK(none.radiance.allFinite());
  CHECK_THROWS_WITH(shade_from_probes(points, grid, valid, incident, lobes, nullptr, control),
                    Catch::Contains("needs the scene's rays"));
  // Incident light in another basis than the lobes' is refused, not misread.
  valid = {1, 1};
  const std::vector<Eigen::MatrixX3d> nine(2, Eigen::MatrixX3d::Zero(9, 3));
  CHECK_THROWS_WITH(shade_from_probes(points, grid, valid, nine, lobes, &caster, control),
                    Catch::Contains("incident light of 9 coefficients for lobes of 4"));
}

TEST_CASE("the normal bias moves a point of the traced scene off its own surface", "[probes]") {
  const auto basis = sh_basis(2);
  // A floor slab whose top is y = 0; probes at y = 0.05 (dark) and 1.05 (lit).
  Mesh floor = make_box(1.0f);
  for (Eigen::Vector3f& p : floor.positions)
    p = Eigen::Vector3f(50 * p.x(), p.y() - 0.5f, 50 * p.z());
  const RayCaster caster(floor);
  ProbeGrid grid;
  grid.origin = {0, 0.05f, 0};
  grid.spacing = 1;
  grid.counts = {1, 2, 1};
  std::vector<Eigen::MatrixX3d> incident(2, Eigen::MatrixX3d::Zero(4, 3));
  incident[1].row(0).setConstant(std::sqrt(4 * M_PI));  // radiance 1 at the upper probe
  Mesh points;                                          // a vertex of the floor's top face
  points.positions = {{0, 0, 0}};
  points.normals = {{0, 1, 0}};
  const Eigen::MatrixXd lobes = cosine_lobes(*basis, points.normals, DirectionSet::fibonacci(2048));
  ProbeLookup lookup;
  lookup.normal_bias = 0.5f;  // half a spacing: to y = 0.5, 0.45 of the way to the lit probe
  const ProbeShading shaded =
      shade_from_probes(points, grid, {1, 1}, incident, lobes, &caster, lookup);
  // The upper probe's light is a constant 1, so the radiance is its weight;
  // a point left on the floor (its ray hitting its own face) would get 0.
  CHECK(shaded.radiance(0, 0) == Approx(0.45).epsilon(1e-3));
  CHECK(shaded.unseen == 0);
}

namespace {

const char* kProbeScene = R"([mesh]
generate = "room"
detail = 0
[[mesh.add]]
generate = "sphere"
detail = 2
position = [0.5, 0, -0.5]
size = 0.6
[receivers]
kind = "probes"
spacing = 1.0
[moving]
generate = "sphere"
detail = 2
position = [-0.5, 0, 0.5]
size = 0.5
[transport]
rays = 256
[basis]
plugin = "sh"
order = 3
[lighting]
constant = [1, 1, 1]
[camera]
width = 64
height = 48
[output]
bake = "probes.h5"
)";

}  // namespace

TEST_CASE("a probe scene bakes, writes version 5, reads back its receivers and renders",
          "[probes]") {
  const fs::path dir = fs::temp_directory_path() / "prt_probe_scene";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "probes.toml") << kProbeScene;
  const SceneSpec scene = SceneSpec::load(dir / "probes.toml", registry());
  REQUIRE(scene.probes());
  REQUIRE(scene.has_moving());
  const Mesh joined = scene.load_mesh();
  CHECK(joined.vertex_count() == make_room(0).vertex_count() + make_sphere(2).vertex_count());
  const BakePlan plan = plan_bake(scene, registry());
  StageTimes times;
  RunOptions options;
  options.quiet = true;
  const BakeData baked = bake_to_file(
      scene, plan, {{scene.bake_path(), FileKind::bake, "bake", true}}, options, times);
  REQUIRE(baked.receivers.probes());
  const BakeData read = read_bake(scene.bake_path());
  CHECK(read.format_version() == kReceiversFormatVersion);
  CHECK(read.receivers.kind == "probes");
  CHECK(read.receivers.grid.counts == baked.receivers.grid.counts);
  CHECK(read.receivers.grid.origin == baked.receivers.grid.origin);
  CHECK(read.receivers.valid == baked.receivers.valid);
  CHECK(std::size_t(read.transfer.vertices()) == read.receivers.grid.count());
  CHECK(read.transfer.exit_rows == 9);
  CHECK(read.mesh.vertex_count() == joined.vertex_count());
  // Compressors and reports get one point per row, never the scene's mesh.
  CHECK(read.row_mesh().vertex_count() == read.receiver_count());
  CHECK(read.row_mesh().triangle_count() == 0);
  CHECK(read.row_mesh().positions[5] == read.receivers.grid.position(5));

  // A crafted /receivers with a valid checksum: each inconsistency refused
  // with a message that says what, and the file named.
  auto crafted = [&](const char* name, const std::function<void(H5::Group&)>& change) {
    const fs::path file = dir / name;
    fs::copy_file(scene.bake_path(), file, fs::copy_options::overwrite_existing);
    {
      H5::H5File h5(file.string(), H5F_ACC_RDWR);
      H5::Group receivers = h5.openGroup("receivers");
      change(receivers);
    }
    seal_bake_file(file, kReceiversFormatVersion);
    return file;
  };
  auto set_number = [](H5::Group& g, const char* attribute, double value) {
    g.openAttribute(attribute).write(H5::PredType::NATIVE_DOUBLE, &value);
  };
  H5::Exception::dontPrint();
  CHECK_THROWS_WITH(
      read_bake(crafted("counts.h5", [&](H5::Group& g) { set_number(g, "count_x", 3); })),
      Catch::Contains("counts.h5") && Catch::Contains("rows for 72 probes"));
  CHECK_THROWS_WITH(
      read_bake(crafted("spacing.h5", [&](H5::Group& g) { set_number(g, "spacing", -1); })),
      Catch::Contains("spacing.h5") && Catch::Contains("is not a grid"));
  CHECK_THROWS_WITH(
      read_bake(crafted("huge.h5", [&](H5::Group& g) { set_number(g, "count_z", 1e12); })),
      Catch::Contains("huge.h5") && Catch::Contains("out of range"));
  CHECK_THROWS_WITH(read_bake(crafted("valid.h5",
                                      [&](H5::Group& g) {
                                        g.unlink("valid");
                                        const std::vector<std::uint8_t> two(
                                            read.receivers.valid.size(), 2);
                                        const hsize_t dims[2] = {two.size(), 1};
                                        g.createDataSet("valid", H5::PredType::NATIVE_UINT8,
                                                        H5::DataSpace(2, dims))
                                            .write(two.data(), H5::PredType::NATIVE_UINT8);
                                      })),
                    Catch::Contains("valid.h5") && Catch::Contains("other than 0 or 1"));
  const Rendered image = render(scene, read, registry(), times);
  CHECK(image.image.width == 64);
  // Every displayed vertex, the moving sphere's included, shaded and finite;
  // under constant unit light nothing exceeds the albedo (0.8) by much.
  CHECK(std::size_t(image.vertex_radiance.rows()) ==
        joined.vertex_count() + scene.load_moving().vertex_count());
  CHECK(image.vertex_radiance.allFinite());
  CHECK(image.vertex_radiance.maxCoeff() < 0.9f);
  CHECK(image.vertex_radiance.maxCoeff() > 0.1f);
  fs::remove_all(dir);
}

TEST_CASE("probe scenes refuse what probes do not receive, each at its key", "[probes]") {
  auto parse = [](const std::string& text) {
    return SceneSpec::parse(text, fs::temp_directory_path() / "scene.toml", registry());
  };
  const std::string base = R"([mesh]
generate = "room"
[lighting]
constant = [1, 1, 1]
)";
  CHECK_THROWS_WITH(parse(base + "[moving]\ngenerate = \"sphere\"\n"),
                    Catch::Contains("[moving]: a moving object is shaded from probes"));
  CHECK_THROWS_WITH(parse(base + "[receivers]\nkind = \"probes\"\n[material]\nbrdf = \"phong\"\n"),
                    Catch::Contains("glossy material"));
  CHECK_THROWS_WITH(parse(base + "[receivers]\nkind = \"probes\"\n[transport]\nbounces = 1\n"),
                    Catch::Contains("bounces = 0"));
  CHECK_THROWS_WITH(parse(base + "[receivers]\nkind = \"probes\"\n[moving]\nsize = 1\n"),
                    Catch::Contains("[moving]: give exactly one of"));
  CHECK_THROWS_WITH(parse(base + "[[mesh.add]]\nposition = [0, 0, 0]\n"),
                    Catch::Contains("[[mesh.add]]: give exactly one of"));
  CHECK_THROWS_WITH(parse(base + "[[mesh.add]]\ngenerate = \"sphere\"\nsize = -1\n"),
                    Catch::Contains("size"));
  CHECK_THROWS_WITH(parse(base + "[receivers]\nkind = \"voxels\"\n"),
                    Catch::Contains("kind") && Catch::Contains("vertices, texels, probes"));
  CHECK_THROWS_WITH(parse(base + "[receivers]\nkind = \"probes\"\nspacing = 0\n"),
                    Catch::Contains("spacing"));
}

TEST_CASE("probes in slabs through a checkpoint equal probes at once, and resume", "[probes]") {
  const fs::path dir = fs::temp_directory_path() / "prt_probe_slabs";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::string text = kProbeScene;  // 2,268 probes: several slabs
  text.replace(text.find("spacing = 1.0"), 13, "spacing = 0.45");
  std::ofstream(dir / "probes.toml") << text;
  const SceneSpec scene = SceneSpec::load(dir / "probes.toml", registry());
  const BakePlan plan = plan_bake(scene, registry());
  StageTimes times;
  const BakeData whole = bake(scene, plan, RunOptions{true}, times);  // no checkpoint
  REQUIRE(whole.receiver_count() > 2 * kProjectionBlock);
  const CheckpointStore store(dir / "probes.h5", bake_key(scene, plan), "test");
  RunOptions options{true};
  options.checkpoint = &store;
  options.slab_vertices = 1;  // one block of the projection a slab: several slabs
  const BakeData slabbed = bake(scene, plan, options, times);
  CHECK(slabbed.transfer.coefficients == whole.transfer.coefficients);
  CHECK(slabbed.receivers.valid == whole.receivers.valid);
  CHECK(slabbed.metrics == whole.metrics);
  // A slab lost (never written by a killed run) is traced again; a damaged
  // validity part is refused, naming it.
  auto part = [](const char* what, std::size_t first, std::size_t last) {
    char name[96];
    std::snprintf(name, sizeof name, "%s.rows-%012zu-%012zu", what, first, last);
    return std::string(name);
  };
  REQUIRE(fs::remove(store.folder() / part("transfer", 0, kProjectionBlock)));
  const BakeData resumed = bake(scene, plan, options, times);
  CHECK(resumed.transfer.coefficients == whole.transfer.coefficients);
  CHECK(resumed.receivers.valid == whole.receivers.valid);
  store.save(part("valid", kProjectionBlock, 2 * kProjectionBlock),
             std::vector<std::int32_t>(3, 1));
  CHECK_THROWS_WITH(bake(scene, plan, options, times), Catch::Contains("valid.rows"));
  fs::remove_all(dir);
}
