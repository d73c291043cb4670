#include <stb/stb_image_write.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "prt/environment.hpp"
#include "prt/error.hpp"
#include "prt/sh.hpp"

using namespace prt;

namespace {
// An SH basis defined in the test, with or without the rotation capability.
class TestSH : public Basis {
 public:
  TestSH(int order, bool rotates) : order_(order), rotates_(rotates) {}
  int size() const override { return order_ * order_; }
  bool orthonormal() const override { return true; }
  Eigen::MatrixXd evaluate(const Directions& d) const override { return sh::evaluate(order_, d); }
  bool can_rotate() const override { return rotates_; }
  Eigen::MatrixXd rotation_matrix(const Eigen::Matrix3d& r) const override {
    return sh::rotation(order_, r);
  }

 private:
  int order_;
  bool rotates_;
};

// A map sampled from a smooth, band-limited function of direction.
Environment smooth_map(int width, int height) {
  std::vector<float> rgb;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const Eigen::Vector3d d = equirect_direction((x + 0.5) / width, (y + 0.5) / height);
      const double value = 1.0 + 0.5 * d.y() + 0.3 * d.x() * d.z();
      rgb.insert(rgb.end(), {float(value), float(2 * value), float(0.5 * value)});
    }
  return Environment::from_pixels(width, height, rgb);
}
}  // namespace

TEST_CASE("a constant environment projects to its DC term", "[environment]") {
  const Environment env = Environment::constant({2, 2, 2});
  const Eigen::MatrixX3d l = env.project(TestSH(4, true));
  CHECK(l(0, 0) == Approx(2 * std::sqrt(4 * M_PI)).epsilon(1e-9));
  CHECK(l.bottomRows(15).cwiseAbs().maxCoeff() < 1e-9);
}

TEST_CASE("projecting a sampled smooth map recovers its coefficients", "[environment]") {
  const Eigen::MatrixX3d l = smooth_map(512, 256).project(TestSH(3, true));
  const double c = std::sqrt(4 * M_PI);
  CHECK(l(0, 0) == Approx(c).epsilon(1e-4));
  CHECK(l(0, 1) == Approx(2 * c).epsilon(1e-4));
  CHECK(l(1, 0) == Approx(0.5 * std::sqrt(4 * M_PI / 3)).epsilon(1e-4));  // y term
  CHECK(std::abs(l(3, 0)) < 1e-6);                                        // no x term
}

TEST_CASE("environment rotation: coefficient rotation agrees with re-sampling",
          "[environment][rotation]") {
  Environment env = smooth_map(512, 256);
  env.set_rotation(rotation_about_up(70) *
                   Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitX()).toRotationMatrix());
  const Eigen::MatrixX3d by_rotation = env.project(TestSH(3, true));
  const Eigen::MatrixX3d by_sampling = env.project(TestSH(3, false));
  CHECK((by_rotation - by_sampling).cwiseAbs().maxCoeff() < 2e-3);
  // The rotated DC term is unchanged, the y term is not.
  CHECK(by_rotation(0, 0) == Approx(std::sqrt(4 * M_PI)).epsilon(1e-4));
}

TEST_CASE("radiance lookup applies intensity and rotation", "[environment]") {
  std::vector<float> rgb(8 * 4 * 3, 0.f);
  for (int x = 0; x < 8; ++x)
    for (int c = 0; c < 3; ++c) rgb[(0 * 8 + x) * 3 + c] = 5.f;  // top row bright
  Environment env = Environment::from_pixels(8, 4, rgb);
  CHECK(env.radiance({0, 1, 0}).x() == Approx(5.f));
  CHECK(env.radiance({0, -1, 0}).x() == Approx(0.f));
  env.set_intensity(2.f);
  CHECK(env.radiance({0, 1, 0}).x() == Approx(10.f));
  env.set_rotation(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix());
  CHECK(env.radiance({0, -1, 0}).x() == Approx(10.f));
}

TEST_CASE("Radiance HDR maps load like EXR maps", "[environment]") {
  // A 4 x 2 RGBE file written by stb_image_write.
  const auto file = std::filesystem::temp_directory_path() / "prt_test.hdr";
  std::vector<float> rgb(4 * 2 * 3);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = 0.5f * float(i % 7);
  REQUIRE(stbi_write_hdr(file.c_str(), 4, 2, 3, rgb.data()));
  const Environment env = Environment::load(file);
  CHECK(env.width() == 4);
  CHECK(env.height() == 2);
  for (std::size_t i = 0; i < rgb.size(); ++i)
    CHECK(env.pixels()[i] == Approx(rgb[i]).margin(0.02));
  CHECK_THROWS_WITH(Environment::load("sky.png"),
                    Catch::Contains("unknown environment map format"));
}

TEST_CASE("unreadable EXR files are refused with the file name", "[environment]") {
  CHECK_THROWS_WITH(Environment::load_exr("/nonexistent/sky.exr"), Catch::Contains("not found"));
  const auto bad = std::filesystem::temp_directory_path() / "prt_bad.exr";
  std::ofstream(bad) << "not an exr";
  CHECK_THROWS_WITH(Environment::load_exr(bad), Catch::Contains("prt_bad.exr"));
}

TEST_CASE("the separable SH projection of an equirectangular map equals the per-texel one",
          "[environment][sh]") {
  // Random texels (not band-limited) on an odd-sized grid: every texel and
  // row weight must enter exactly as in the quadrature through directions.
  const int width = 67, height = 31;
  std::vector<float> rgb(width * height * 3);
  std::uint32_t state = 12345;
  for (float& v : rgb) v = float((state = state * 1664525u + 1013904223u) >> 8) / float(1 << 24);
  Environment env = Environment::from_pixels(width, height, rgb);
  env.set_intensity(2.f);
  for (int order : {1, 2, 5, 10}) {
    const Eigen::MatrixX3d generic = env.project(TestSH(order, true));  // through directions
    const Eigen::MatrixX3d separable =
        2.0 * sh::project_equirect(order, width, height, env.pixels().data());
    INFO("order " << order);
    CHECK((separable - generic).cwiseAbs().maxCoeff() < 1e-12 * generic.cwiseAbs().maxCoeff());
  }
  CHECK(sh::project_equirect(0, width, height, rgb.data()).rows() == 0);
}
