// The map sampler of the ground truth: its density is a density, its samples
// lie in the texel they report, and it integrates a map exactly in
// expectation (a wrong pdf or a flipped convention biases every reference).
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "prt/direction_set.hpp"
#include "prt/environment.hpp"
#include "prt/environment_sampler.hpp"

using namespace prt;

namespace {

// A dim map with a small bright patch (a sun) near one pole and a gradient.
Environment sunny_map(int width, int height) {
  std::vector<float> rgb(std::size_t(width) * height * 3);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c) {
        const bool sun = y >= 3 && y < 5 && x >= 40 && x < 43;
        rgb[(std::size_t(y) * width + x) * 3 + c] = sun ? 5000.f : 0.1f + 0.01f * (x % 7) + c;
      }
  Environment map = Environment::from_pixels(width, height, rgb);
  map.set_rotation(rotation_about_up(37.0));
  return map;
}

// The integral over the sphere of a function constant on each texel of a
// 64 x 32 map: value(centre) x solid angle, summed.
template <class Value>
double integral_over_texels(const Value& value) {
  double sum = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 64; ++x)
      sum += value(Eigen::Vector2d((x + 0.5) / 64, (y + 0.5) / 32)) * 2.0 * M_PI / 64 *
             (std::cos(M_PI * y / 32) - std::cos(M_PI * (y + 1) / 32));
  return sum;
}

}  // namespace

TEST_CASE("the environment sampler's density integrates to one over the sphere", "[environment]") {
  const Environment map = sunny_map(64, 32);
  const EnvironmentSampler sampler(map);
  const double total =
      integral_over_texels([&](const Eigen::Vector2d& uv) { return sampler.pdf_at(uv); });
  CHECK(total == Approx(1.0).epsilon(1e-12));
}

TEST_CASE("an environment sample lies in the texel whose density and radiance it reports",
          "[environment]") {
  const Environment map = sunny_map(64, 32);
  const EnvironmentSampler sampler(map);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int inside = 0;
  const int count = 20000;
  for (int i = 0; i < count; ++i) {
    const EnvironmentSampler::Sample s = sampler.sample(u(rng), u(rng));
    REQUIRE(s.direction.norm() == Approx(1.0).epsilon(1e-12));
    const Eigen::Vector2d uv = map.uv_of(s.direction);
    const bool same_texel =
        int(uv.x() * 64) == int(s.uv.x() * 64) && int(uv.y() * 32) == int(s.uv.y() * 32);
    inside += same_texel;
    if (same_texel) {
      CHECK(s.pdf == Approx(sampler.pdf(s.direction)).epsilon(1e-12));
      CHECK(map.texel_radiance_at(s.uv).isApprox(map.texel_radiance(s.direction)));
    }
  }
  // Only a sample on a texel's very edge may round into its neighbour.
  CHECK(inside >= count - 2);
}

TEST_CASE("importance sampling integrates the map exactly in expectation", "[environment]") {
  const Environment map = sunny_map(64, 32);
  const EnvironmentSampler sampler(map);
  const double exact = integral_over_texels(
      [&](const Eigen::Vector2d& uv) { return double(map.texel_radiance_at(uv).x()); });
  // Stratified: with the density proportional to the luminance the
  // estimator's variance is small, a biased one misses by far more.
  const int side = 128;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> jitter(0.0, 1.0);
  double sum = 0;
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j) {
      const auto s = sampler.sample((i + jitter(rng)) / side, (j + jitter(rng)) / side);
      sum += map.texel_radiance_at(s.uv).x() / s.pdf;
    }
  CHECK(sum / (side * side) == Approx(exact).epsilon(2e-3));
}

TEST_CASE("the sampler inverts its CDF: each texel takes its share of the unit square",
          "[environment]") {
  // The sun's rows and columns take most of [0, 1); the dim ones a sliver
  // each: a search that stops short of the right interval moves whole
  // slivers to a neighbour.
  const int width = 64, height = 32;
  const Environment map = sunny_map(width, height);
  const EnvironmentSampler sampler(map);
  auto probability = [&](Eigen::Index texel) {
    const Eigen::Index y = texel / width;
    return sampler.density(texel) * 2.0 * M_PI / width *
           (std::cos(M_PI * y / height) - std::cos(M_PI * (y + 1) / height));
  };
  // Rows: u1 on a fine grid (u2 fixed); the drawn row never goes back and
  // each row's share of the grid is its probability.
  const int steps = 200000;
  std::vector<double> row_share(height, 0.0), row_probability(height, 0.0);
  for (Eigen::Index t = 0; t < width * height; ++t) row_probability[t / width] += probability(t);
  Eigen::Index previous = 0;
  for (int i = 0; i < steps; ++i) {
    const EnvironmentSampler::Drawn drawn = sampler.draw((i + 0.5) / steps, 0.5);
    const Eigen::Index row = drawn.texel / width;
    REQUIRE(row >= previous);
    previous = row;
    row_share[std::size_t(row)] += 1.0 / steps;
  }
  for (int y = 0; y < height; ++y) CHECK(row_share[y] == Approx(row_probability[y]).margin(2e-5));
  // Columns of the sun's row (u1 inside it) and of a dim row.
  for (const int y : {3, 20}) {
    double below = 0;
    for (int r = 0; r < y; ++r) below += row_probability[r];
    const double u1 = below + 0.5 * row_probability[y];
    double row_total = 0;
    for (int x = 0; x < width; ++x) row_total += probability(Eigen::Index(y) * width + x);
    std::vector<double> share(width, 0.0);
    Eigen::Index last = 0;
    for (int i = 0; i < steps; ++i) {
      const EnvironmentSampler::Drawn drawn = sampler.draw(u1, (i + 0.5) / steps);
      REQUIRE(drawn.texel / width == y);
      REQUIRE(drawn.texel % width >= last);
      last = drawn.texel % width;
      share[std::size_t(last)] += 1.0 / steps;
    }
    for (int x = 0; x < width; ++x)
      CHECK(share[x] == Approx(probability(Eigen::Index(y) * width + x) / row_total).margin(2e-5));
  }
  // The ends and the cells' boundaries k / count.
  for (const double u : {0.0, std::nextafter(1.0, 0.0), 1.0 / height, 17.0 / height, 0.5}) {
    const EnvironmentSampler::Drawn drawn = sampler.draw(u, u);
    CHECK(drawn.texel >= 0);
    CHECK(drawn.texel < width * height);
    const EnvironmentSampler::Sample sample = sampler.sample(u, u);
    CHECK((sample.direction - drawn.direction).norm() == 0.0);
    CHECK(sample.pdf == sampler.density(drawn.texel));
  }
}
