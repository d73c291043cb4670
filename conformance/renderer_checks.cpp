// Conformance checks run over every renderer plug-in (one ctest entry each;
// an OpenGL one under Xvfb). Each draws small generated scenes whose image
// is known: a sphere of constant radiance, a background, two surfaces one
// behind the other, and the same radiance given as transfer and light.
#include <cmath>

#include "kit.hpp"
#include "prt/environment.hpp"
#include "prt/renderer.hpp"

namespace prt::conformance {

namespace {

constexpr int kWidth = 64, kHeight = 48;

Camera front_camera() {
  Camera camera;
  camera.position = {0, 0, 3};
  camera.target = {0, 0, 0};
  camera.width = kWidth;
  camera.height = kHeight;
  return camera;
}

std::shared_ptr<Renderer> make(Kit& kit) {
  Params params;
  return kit.registry.create<Renderer>(kit.plugin, params);
}

// The largest per-channel distance from `expected` at pixel (x, y).
double off_by(const Image& image, int x, int y, const Eigen::Vector3f& expected) {
  const float* p = image.at(x, y);
  double worst = 0;
  for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(double(p[c]) - expected[c]));
  return worst;
}

// 8-bit framebuffers may round: a renderer is held to 1/255 of the value.
constexpr double kTolerance = 1.0 / 255 + 1e-5;

// Per-vertex radiance drawn from the front camera, no background.
RenderInput radiance_input(const Mesh& mesh, const Eigen::MatrixX3f& radiance) {
  RenderInput input;
  input.mesh = &mesh;
  input.vertex_radiance = &radiance;
  input.camera = front_camera();
  return input;
}

void mesh_translate(Mesh& mesh, const Eigen::Vector3f& by) {
  for (auto& p : mesh.positions) p += by;
}

}  // namespace

// 1. The image's size, finite and non-negative values.
static void renderer_check_0(Kit& kit) {
  const Mesh sphere = make_sphere(3);
  const Eigen::MatrixX3f radiance =
      Eigen::MatrixX3f::Constant(Eigen::Index(sphere.vertex_count()), 3, 0.5f);
  const RenderInput input = radiance_input(sphere, radiance);
  const Image image = make(kit)->render(input);
  KIT_CHECK_EQUAL(kit, image.width, kWidth);
  KIT_CHECK_EQUAL(kit, image.height, kHeight);
  KIT_CHECK_EQUAL(kit, double(image.rgb.size()), 3.0 * kWidth * kHeight);
  bool finite = true, non_negative = true;
  for (float v : image.rgb)
    finite = finite && std::isfinite(v), non_negative = non_negative && v >= 0;
  KIT_CHECK(kit, finite);
  KIT_CHECK(kit, non_negative);
}

// 2. A surface of constant radiance shows it; uncovered pixels show the
//    background (or black without one).
static void renderer_check_1(Kit& kit) {
  const Mesh sphere = make_sphere(3);
  const Eigen::Vector3f colour(0.25f, 0.5f, 0.75f), sky(0.1f, 0.2f, 0.3f);
  const Eigen::MatrixX3f radiance =
      colour.transpose().replicate(Eigen::Index(sphere.vertex_count()), 1);
  RenderInput input = radiance_input(sphere, radiance);
  auto renderer = make(kit);
  const Image bare = renderer->render(input);
  KIT_CHECK_AT_MOST(kit, off_by(bare, kWidth / 2, kHeight / 2, colour), kTolerance);
  KIT_CHECK_AT_MOST(kit, off_by(bare, 0, 0, Eigen::Vector3f::Zero()), kTolerance);
  const Environment background = Environment::constant(sky);
  input.background = &background;
  const Image with_sky = renderer->render(input);
  KIT_CHECK_AT_MOST(kit, off_by(with_sky, kWidth / 2, kHeight / 2, colour), kTolerance);
  KIT_CHECK_AT_MOST(kit, off_by(with_sky, 0, 0, sky), kTolerance);
  KIT_CHECK_AT_MOST(kit, off_by(with_sky, kWidth - 1, kHeight - 1, sky), kTolerance);
}

// 3. Of two surfaces on one line of sight, the nearer is drawn, whichever
//    comes first in the mesh.
static void renderer_check_2(Kit& kit) {
  for (const bool near_first : {true, false}) {
    Mesh near = make_sphere(2, 0.4f), far = make_sphere(2, 1.0f);
    mesh_translate(far, {0, 0, -2});
    const Mesh& a = near_first ? near : far;
    const Mesh& b = near_first ? far : near;
    Mesh both = a;
    const auto offset = std::uint32_t(a.vertex_count());
    both.positions.insert(both.positions.end(), b.positions.begin(), b.positions.end());
    both.normals.insert(both.normals.end(), b.normals.begin(), b.normals.end());
    for (auto t : b.triangles)
      both.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    Eigen::MatrixX3f radiance(Eigen::Index(both.vertex_count()), 3);
    const Eigen::RowVector3f red(0.8f, 0.1f, 0.1f), blue(0.1f, 0.1f, 0.8f);
    for (Eigen::Index v = 0; v < radiance.rows(); ++v)
      radiance.row(v) = (v < Eigen::Index(offset)) == near_first ? red : blue;
    const RenderInput input = radiance_input(both, radiance);
    const Image image = make(kit)->render(input);
    Kit::Note note(kit, near_first ? "the nearer sphere first in the mesh"
                                   : "the nearer sphere last in the mesh");
    KIT_CHECK_AT_MOST(kit, off_by(image, kWidth / 2, kHeight / 2, red.transpose()), kTolerance);
  }
}

// 4. Radiance given as transfer and light draws as the same radiance given
//    per vertex (albedo applied to the transfer's).
static void renderer_check_3(Kit& kit) {
  const Mesh sphere = make_sphere(3);
  const auto v = Eigen::Index(sphere.vertex_count());
  TransferSignal signal;
  signal.coefficients.resize(v, 4);
  for (Eigen::Index p = 0; p < v; ++p) {
    const Eigen::Vector3f n = sphere.normals[std::size_t(p)];
    signal.coefficients.row(p) << 0.5f, 0.2f * n.x(), 0.2f * n.y(), 0.2f * n.z();
  }
  const CompressedTransfer transfer = exact_form(signal);
  Eigen::MatrixX3d light(4, 3);
  light << 0.6, 0.5, 0.4, 0.3, 0.0, -0.2, 0.1, 0.4, 0.0, 0.5, 0.2, 0.3;
  const Eigen::Vector3f albedo(0.9f, 0.7f, 0.5f);
  Eigen::MatrixX3f radiance =
      (signal.coefficients.cast<double>() * light).cast<float>().cwiseMax(0.0f);
  for (int c = 0; c < 3; ++c) radiance.col(c) *= albedo[c];
  auto renderer = make(kit);
  RenderInput by_transfer;
  by_transfer.mesh = &sphere;
  by_transfer.transfer = &transfer;
  by_transfer.light = light;
  by_transfer.albedo = albedo;
  by_transfer.camera = front_camera();
  const Image a = renderer->render(by_transfer);
  const RenderInput by_radiance = radiance_input(sphere, radiance);
  const Image b = renderer->render(by_radiance);
  double worst = 0;
  for (std::size_t i = 0; i < a.rgb.size() && a.rgb.size() == b.rgb.size(); ++i)
    worst = std::max(worst, double(std::abs(a.rgb[i] - b.rgb[i])));
  KIT_CHECK_EQUAL(kit, double(a.rgb.size()), double(b.rgb.size()));
  KIT_CHECK_AT_MOST(kit, worst, 2 * kTolerance);
}

// 5. The same input draws the same image.
static void renderer_check_4(Kit& kit) {
  const Mesh sphere = make_sphere(3);
  Eigen::MatrixX3f radiance(Eigen::Index(sphere.vertex_count()), 3);
  for (Eigen::Index p = 0; p < radiance.rows(); ++p)
    radiance.row(p) = (sphere.normals[std::size_t(p)].array() * 0.5f + 0.5f).matrix().transpose();
  const RenderInput input = radiance_input(sphere, radiance);
  auto renderer = make(kit);
  const Image first = renderer->render(input);
  const Image second = renderer->render(input);
  KIT_CHECK(kit, first.rgb == second.rgb);
}

std::vector<Check> renderer_checks() {
  return {
      {"draws an image of the camera's size, finite and non-negative", "[conformance]",
       renderer_check_0},
      {"a surface of constant radiance shows it; uncovered pixels show the background",
       "[conformance]", renderer_check_1},
      {"the nearer of two surfaces is drawn, whatever the triangle order", "[conformance]",
       renderer_check_2},
      {"transfer and light draw as the same radiance given per vertex", "[conformance]",
       renderer_check_3},
      {"the same input draws the same image", "[conformance]", renderer_check_4},
  };
}

}  // namespace prt::conformance
