#include "prt/ground_truth.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>
#include <random>

#include "prt/environment.hpp"
#include "prt/environment_sampler.hpp"
#include "prt/error.hpp"
#include "prt/progress.hpp"
#include "prt/transport.hpp"

namespace prt {

CosineHemisphere::CosineHemisphere(const Eigen::Vector3d& normal)
    : normal_(normal),
      tangent_((std::abs(normal.x()) > 0.9 ? Eigen::Vector3d(0, 1, 0) : Eigen::Vector3d(1, 0, 0))
                   .cross(normal)
                   .normalized()),
      bitangent_(normal.cross(tangent_)) {}

Eigen::Vector3d CosineHemisphere::sample(double u1, double u2) const {
  const double r = std::sqrt(u1), phi = 2.0 * M_PI * u2;
  return r * std::cos(phi) * tangent_ + r * std::sin(phi) * bitangent_ +
         std::sqrt(1.0 - u1) * normal_;
}

namespace {

// Interleaves 16-bit x and y into a 32-bit Morton code.
std::uint32_t interleave(std::uint32_t x, std::uint32_t y) {
  auto spread = [](std::uint32_t a) {
    a = (a | (a << 8)) & 0x00FF00FFu;
    a = (a | (a << 4)) & 0x0F0F0F0Fu;
    a = (a | (a << 2)) & 0x33333333u;
    return (a | (a << 1)) & 0x55555555u;
  };
  return spread(x) | (spread(y) << 1);
}

// Orders a set's directions along a Morton curve of their octahedral map, so
// that a vertex's consecutive rays leave in nearby directions and meet the
// same parts of the BVH (as the bake's Fibonacci spiral does).
void sort_along_sphere(SharedSamples& samples) {
  const std::size_t s = samples.directions.size();
  std::vector<std::pair<std::uint32_t, std::uint32_t>> keyed(s);
  for (std::size_t k = 0; k < s; ++k) {
    const Eigen::Vector3f& d = samples.directions[k];
    const float norm = std::abs(d.x()) + std::abs(d.y()) + std::abs(d.z());
    float x = d.x() / norm, y = d.y() / norm;
    if (d.z() < 0) {  // fold the lower half over the diagonals
      const float fx = (1 - std::abs(y)) * (x >= 0 ? 1.f : -1.f);
      y = (1 - std::abs(x)) * (y >= 0 ? 1.f : -1.f), x = fx;
    }
    const auto cell = [](float t) {
      return std::uint32_t(std::clamp((t + 1.f) * 32767.5f, 0.f, 65535.f));
    };
    keyed[k] = {interleave(cell(x), cell(y)), std::uint32_t(k)};
  }
  std::sort(keyed.begin(), keyed.end());
  SharedSamples sorted{samples.local, {}, {}};
  sorted.directions.reserve(s), sorted.weighted.reserve(s);
  for (const auto& [key, k] : keyed)
    sorted.directions.push_back(samples.directions[k]),
        sorted.weighted.push_back(samples.weighted[k]);
  samples = std::move(sorted);
}

}  // namespace

SharedSamples draw_shared_samples(const Environment& environment, const EnvironmentSampler* sampler,
                                  int side, std::uint64_t seed, std::size_t block) {
  // Seeded per block, so results do not depend on scheduling.
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + block);
  std::uniform_real_distribution<double> jitter(0.0, 1.0);
  const int per_strategy = side * side, strategies = sampler ? 2 : 1;
  SharedSamples out;
  out.local = !sampler;
  out.directions.reserve(std::size_t(strategies * per_strategy));
  out.weighted.reserve(out.directions.capacity());
  const Eigen::Index width = environment.width(), height = environment.height();
  // Balance heuristic over both strategies: f / (N p_sphere + N p_map).
  const double sphere_pdf = 1.0 / (4.0 * M_PI);
  for (int k = 0; k < strategies * per_strategy; ++k) {
    // Stratified in [0,1)^2 within each strategy.
    const int stratum = k % per_strategy;
    const double u1 = (stratum / side + jitter(rng)) / side;
    const double u2 = (stratum % side + jitter(rng)) / side;
    if (!sampler) {  // cosine-weighted about z, the constant map's radiance
      const double r = std::sqrt(u1), phi = 2.0 * M_PI * u2;
      out.directions.emplace_back(float(r * std::cos(phi)), float(r * std::sin(phi)),
                                  float(std::sqrt(1.0 - u1)));
      out.weighted.push_back(environment.texel_radiance_at({0.5, 0.5}).cast<double>() /
                             per_strategy);
      continue;
    }
    Eigen::Vector3d d;
    Eigen::Index texel;
    if (k < per_strategy) {  // uniform over the sphere (area-preserving map)
      const double z = 1.0 - 2.0 * u1, r = std::sqrt(std::max(0.0, 1.0 - z * z));
      const double phi = 2.0 * M_PI * u2;
      d = {r * std::cos(phi), r * std::sin(phi), z};
      texel = sampler->texel_at(environment.uv_of(d));
    } else {
      const EnvironmentSampler::Drawn drawn = sampler->draw(u1, u2);
      d = drawn.direction, texel = drawn.texel;
    }
    const Eigen::Vector2d uv((texel % width + 0.5) / width, (texel / width + 0.5) / height);
    const double mixture = per_strategy * (sphere_pdf + sampler->density(texel));
    out.directions.push_back(d.cast<float>());
    out.weighted.push_back(environment.texel_radiance_at(uv).cast<double>() / (M_PI * mixture));
  }
  if (sampler) sort_along_sphere(out);
  return out;
}

namespace {

// One task's estimator of the reference at a block's vertices: each vertex
// traces the block's shared directions above its tangent plane and sums
// what escapes. Its buffers are reused block after block.
class BlockEstimator {
 public:
  BlockEstimator(const Mesh& mesh, const RayCaster& caster, const Reflectance& reflectance)
      : mesh_(mesh), caster_(caster), reflectance_(reflectance) {}

  // Radiance of `count` vertices (rows of `out`).
  void estimate(const std::uint32_t* vertices, std::size_t count, const SharedSamples& samples,
                Eigen::MatrixX3f& out) {
    if (samples.local) {
      for (std::size_t i = 0; i < count; ++i)
        out.row(Eigen::Index(vertices[i])) = local_radiance(vertices[i], samples).transpose();
      return;
    }
    // World directions: the bake's own trace, straight into Embree's stream.
    const std::size_t s = samples.directions.size(), words = VisibilityBits::words_for(s);
    flat_.resize(3 * s);
    for (std::size_t k = 0; k < s; ++k)
      for (int c = 0; c < 3; ++c) flat_[3 * k + c] = samples.directions[k][c];
    bits_.resize(count * words);
    rays_ += caster_.trace_visibility(mesh_, vertices, count, flat_.data(), s, bits_.data());
    for (std::size_t i = 0; i < count; ++i) {
      const std::size_t v = vertices[i];
      const Eigen::Vector3f n = mesh_.normals[v];
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (std::size_t w = 0; w < words; ++w)
        for (std::uint64_t word = bits_[i * words + w]; word; word &= word - 1) {
          const std::size_t k = 64 * w + std::size_t(__builtin_ctzll(word));
          double weight = samples.directions[k].dot(n);  // escaped: above the plane
          if (reflectance_) weight *= reflectance_(v, samples.directions[k].cast<double>());
          sum += weight * samples.weighted[k];
        }
      out.row(Eigen::Index(v)) = sum.cast<float>().transpose();
    }
  }
  std::uint64_t rays() const { return rays_; }

 private:
  // Cosine-weighted directions in the vertex's own frame: every one traced.
  Eigen::Vector3f local_radiance(std::size_t v, const SharedSamples& samples) {
    const Eigen::Vector3f n = mesh_.normals[v];
    const Eigen::Vector3f o = mesh_.positions[v] + caster_.offset() * n;
    const CosineHemisphere hemisphere(n.cast<double>());
    Eigen::Matrix3f frame;
    frame << hemisphere.tangent().cast<float>(), hemisphere.bitangent().cast<float>(), n;
    const std::size_t s = samples.directions.size();
    origins_.resize(3 * s), flat_.resize(3 * s), escaped_.resize(s);
    for (std::size_t k = 0; k < s; ++k) {
      const Eigen::Vector3f d = frame * samples.directions[k];
      for (int c = 0; c < 3; ++c) origins_[3 * k + c] = o[c], flat_[3 * k + c] = d[c];
    }
    caster_.occluded(origins_.data(), flat_.data(), s, escaped_.data());
    rays_ += s;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < s; ++k) {
      if (!escaped_[k]) continue;
      double weight = 1.0;  // the cosine cancels its density
      if (reflectance_)
        weight = reflectance_(
            v, Eigen::Vector3f(flat_[3 * k], flat_[3 * k + 1], flat_[3 * k + 2]).cast<double>());
      sum += weight * samples.weighted[k];
    }
    return sum.cast<float>();
  }

  const Mesh& mesh_;
  const RayCaster& caster_;
  const Reflectance& reflectance_;
  std::vector<float> origins_, flat_;
  std::vector<std::uint8_t> escaped_;
  std::vector<std::uint64_t> bits_;
  std::uint64_t rays_ = 0;
};

}  // namespace

GroundTruthEstimate ground_truth_estimate(const Mesh& mesh, const Environment& environment,
                                          int samples, std::uint64_t seed, Progress* progress,
                                          const Reflectance& reflectance) {
  RayCaster caster(mesh);
  const std::size_t v_count = mesh.vertex_count();
  // A constant map is sampled best by the cosine alone (zero variance); a real
  // map adds luminance-proportional samples, combined by the balance heuristic.
  const bool use_map = environment.width() * environment.height() > 1;
  std::optional<EnvironmentSampler> sampler;
  if (use_map) sampler.emplace(environment);
  const int strategies = use_map ? 2 : 1;
  const int side = std::max(1, static_cast<int>(std::lround(std::sqrt(samples / strategies))));
  const std::vector<std::uint32_t> order = morton_order(mesh);
  const std::size_t blocks = (v_count + kSharedBlock - 1) / kSharedBlock;
  GroundTruthEstimate out;
  out.radiance.resize(static_cast<Eigen::Index>(v_count), 3);
  std::atomic<std::uint64_t> rays{0};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, 1), [&](const auto& range) {
    BlockEstimator estimator(mesh, caster, reflectance);
    std::size_t done = 0;
    for (std::size_t b = range.begin(); b < range.end(); ++b) {
      const SharedSamples shared =
          draw_shared_samples(environment, sampler ? &*sampler : nullptr, side, seed, b);
      const std::size_t first = b * kSharedBlock, count = std::min(v_count - first, kSharedBlock);
      estimator.estimate(order.data() + first, count, shared, out.radiance);
      done += count;
    }
    rays += estimator.rays();
    if (progress) progress->add(double(done), double(estimator.rays()));
  });
  out.rays = rays;
  return out;
}

Eigen::MatrixX3f ground_truth_radiance(const Mesh& mesh, const Environment& environment,
                                       int samples, std::uint64_t seed, Progress* progress,
                                       const Reflectance& reflectance) {
  return ground_truth_estimate(mesh, environment, samples, seed, progress, reflectance).radiance;
}

}  // namespace prt
