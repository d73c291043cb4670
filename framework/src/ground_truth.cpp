#include "prt/ground_truth.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <bit>
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

std::uint64_t mix(std::uint64_t z) {  // splitmix64's finaliser
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// 16 candidates: two vertices share a stratum's sample with probability
// 1/16, and a batch's pool (93 KB at 256 samples) stays in cache while
// vertices pick from it (64 measured 10% slower). Large sample counts get
// fewer candidates, down to one per stratum once strata pass 2^17 (a pool
// then holds its strata alone: 6 MB at the scene key's 1,048,576 samples).
constexpr int kMaxCandidates = 16;
constexpr std::size_t kMaxPoolEntries = std::size_t(1) << 18;

}  // namespace

void SamplePool::pick(std::uint64_t seed, std::size_t vertex, std::size_t* entries) const {
  // A 64-bit LCG per vertex (Knuth's MMIX constants), seeded by a hash: its
  // top bits choose each candidate (candidates is a power of two).
  std::uint64_t state = mix(seed * 0x9E3779B97F4A7C15ull + mix(vertex + 0xD1B54A32D192ED03ull));
  const int shift = 64 - std::countr_zero(unsigned(candidates));
  for (int j = 0; j < strata; ++j) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const std::size_t c = candidates > 1 ? std::size_t(state >> shift) : 0;
    entries[j] = std::size_t(j) * std::size_t(candidates) + c;
  }
}

SamplePool draw_sample_pool(const Environment& environment, const EnvironmentSampler* sampler,
                            int side, std::uint64_t seed) {
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + 0x5851F42D4C957F2Dull);
  std::uniform_real_distribution<double> jitter(0.0, 1.0);
  const int per_strategy = side * side, strategies = sampler ? 2 : 1;
  SamplePool out;
  out.local = !sampler;
  out.strata = strategies * per_strategy;
  out.candidates = 1;  // a power of two, for pick()'s mask
  while (out.candidates < kMaxCandidates &&
         std::size_t(2 * out.candidates) * std::size_t(out.strata) <= kMaxPoolEntries)
    out.candidates *= 2;
  const std::size_t entries = std::size_t(out.strata) * std::size_t(out.candidates);
  out.entries.reserve(entries);
  const Eigen::Index width = environment.width(), height = environment.height();
  // Balance heuristic over both strategies: f / (N p_sphere + N p_map).
  const double sphere_pdf = 1.0 / (4.0 * M_PI);
  for (int stratum = 0; stratum < out.strata; ++stratum) {
    const int cell = stratum % per_strategy;  // its cell of [0,1)^2 in its strategy
    for (int c = 0; c < out.candidates; ++c) {
      const double u1 = (cell / side + jitter(rng)) / side;
      const double u2 = (cell % side + jitter(rng)) / side;
      if (!sampler) {  // cosine-weighted about z, the constant map's radiance
        const double r = std::sqrt(u1), phi = 2.0 * M_PI * u2;
        out.entries.push_back({Eigen::Vector3f(float(r * std::cos(phi)), float(r * std::sin(phi)),
                                               float(std::sqrt(1.0 - u1))),
                               environment.texel_radiance_at({0.5, 0.5}) / float(per_strategy)});
        continue;
      }
      Eigen::Vector3d d;
      Eigen::Index texel;
      if (stratum < per_strategy) {  // uniform over the sphere (area-preserving map)
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
      out.entries.push_back(
          {d.cast<float>(),
           (environment.texel_radiance_at(uv).cast<double>() / (M_PI * mixture)).cast<float>()});
    }
  }
  return out;
}

namespace {

// One task's estimator of the reference at its vertices, up to 16 at a time:
// each vertex picks a candidate per stratum of every seed's pool, and the
// vertices trace those above their tangent planes in one call (the bake's
// trace, straight into Embree's stream); each seed's rays that escape are
// summed into its own estimate. Its buffers are reused.
class VertexEstimator {
 public:
  // Vertices a call: 16, fewer where their rays would pass 65,536, so the
  // buffers stay ~1 MB a task up to that many rays a vertex (one vertex's
  // own beyond: 21 MB at 1,048,576 samples).
  static std::size_t vertices_per_call(std::size_t rays_per_vertex) {
    return std::clamp<std::size_t>(65536 / std::max<std::size_t>(1, rays_per_vertex), 1, 16);
  }

  VertexEstimator(const Mesh& mesh, const RayCaster& caster, const std::vector<SamplePool>& pools,
                  const std::vector<std::uint64_t>& seeds, const Reflectance& reflectance)
      : mesh_(mesh),
        caster_(caster),
        pools_(pools),
        seeds_(seeds),
        reflectance_(reflectance),
        strata_(std::size_t(pools.front().strata)),
        per_vertex_(strata_ * pools.size()),
        words_(VisibilityBits::words_for(per_vertex_)),
        vertices_a_call_(vertices_per_call(per_vertex_)),
        picked_(vertices_a_call_ * per_vertex_),
        flat_(3 * picked_.size()),
        bits_(vertices_a_call_ * words_) {}

  std::size_t vertices_a_call() const { return vertices_a_call_; }
  // Radiance of `count` <= vertices_a_call() vertices into their rows of each batch.
  void estimate(const std::uint32_t* vertices, std::size_t count,
                std::vector<Eigen::MatrixX3f>& out) {
    for (std::size_t i = 0; i < count; ++i) pick(i, vertices[i]);
    rays_ += caster_.trace_visibility(mesh_, vertices, count, flat_.data(), per_vertex_,
                                      bits_.data(), nullptr, 3 * per_vertex_);
    for (std::size_t i = 0; i < count; ++i) sum(i, vertices[i], out);
  }
  std::uint64_t rays() const { return rays_; }

 private:
  // Slot i's directions: its candidate of each stratum of each pool, in
  // its own frame for local samples.
  void pick(std::size_t i, std::uint32_t v) {
    const Eigen::Vector3f n = mesh_.normals[v];
    Eigen::Matrix3f frame = Eigen::Matrix3f::Identity();
    if (pools_.front().local) {
      const CosineHemisphere hemisphere(n.cast<double>());
      frame << hemisphere.tangent().cast<float>(), hemisphere.bitangent().cast<float>(), n;
    }
    for (std::size_t b = 0; b < pools_.size(); ++b) {
      const std::size_t first = i * per_vertex_ + b * strata_;
      pools_[b].pick(seeds_[b], v, &picked_[first]);
      for (std::size_t j = 0; j < strata_; ++j) {
        const Eigen::Vector3f& drawn = pools_[b].entries[picked_[first + j]].direction;
        const Eigen::Vector3f d = pools_[b].local ? Eigen::Vector3f(frame * drawn) : drawn;
        float* to = &flat_[3 * (first + j)];
        to[0] = d.x(), to[1] = d.y(), to[2] = d.z();
      }
    }
  }

  // Slot i's estimate of each batch: the rays that escaped, batch b's bits
  // from b * strata on.
  void sum(std::size_t i, std::uint32_t v, std::vector<Eigen::MatrixX3f>& out) const {
    const Eigen::Vector3f n = mesh_.normals[v];
    const std::uint64_t* bits = &bits_[i * words_];
    const std::size_t* picked = &picked_[i * per_vertex_];
    const float* flat = &flat_[3 * i * per_vertex_];
    std::size_t b = 0;
    Eigen::Vector3d total = Eigen::Vector3d::Zero();
    auto close_batches_before = [&](std::size_t k) {
      for (; k >= (b + 1) * strata_; ++b, total.setZero())
        out[b].row(Eigen::Index(v)) = total.cast<float>().transpose();
    };
    for (std::size_t w = 0; w < words_; ++w)
      for (std::uint64_t word = bits[w]; word; word &= word - 1) {
        const std::size_t k = 64 * w + std::size_t(std::countr_zero(word));
        close_batches_before(k);
        const Eigen::Vector3f d(flat[3 * k], flat[3 * k + 1], flat[3 * k + 2]);
        // Escaped rays lie above the plane; local samples' cosine cancels their density.
        double weight = pools_[b].local ? 1.0 : double(d.dot(n));
        if (reflectance_) weight *= reflectance_(v, d.cast<double>());  // pi rho replaces albedo 1
        total += weight * pools_[b].entries[picked[k]].weighted.cast<double>();
      }
    close_batches_before(per_vertex_);
  }

  const Mesh& mesh_;
  const RayCaster& caster_;
  const std::vector<SamplePool>& pools_;
  const std::vector<std::uint64_t>& seeds_;
  const Reflectance& reflectance_;
  std::size_t strata_, per_vertex_, words_, vertices_a_call_;
  std::vector<std::size_t> picked_;
  std::vector<float> flat_;
  std::vector<std::uint64_t> bits_;
  std::uint64_t rays_ = 0;
};

}  // namespace

GroundTruthEstimate ground_truth_estimate(const Mesh& mesh, const Environment& environment,
                                          int samples, const std::vector<std::uint64_t>& seeds,
                                          Progress* progress, const Reflectance& reflectance,
                                          const RayCaster* occluders) {
  if (seeds.empty()) throw Error("ground_truth_estimate: no seeds");
  std::optional<RayCaster> own;
  if (!occluders) own.emplace(mesh);
  const RayCaster& caster = occluders ? *occluders : *own;
  const std::size_t v_count = mesh.vertex_count();
  // A constant map is sampled best by the cosine alone (zero variance); a real
  // map adds luminance-proportional samples, combined by the balance heuristic.
  const bool use_map = environment.width() * environment.height() > 1;
  std::optional<EnvironmentSampler> sampler;
  if (use_map) sampler.emplace(environment);
  const int strategies = use_map ? 2 : 1;
  const int side = std::max(1, static_cast<int>(std::lround(std::sqrt(samples / strategies))));
  std::vector<SamplePool> pools;
  for (const std::uint64_t seed : seeds)
    pools.push_back(draw_sample_pool(environment, sampler ? &*sampler : nullptr, side, seed));
  const std::vector<std::uint32_t> order = morton_order(mesh);
  GroundTruthEstimate out;
  out.batches.assign(seeds.size(), Eigen::MatrixX3f(static_cast<Eigen::Index>(v_count), 3));
  std::atomic<std::uint64_t> rays{0};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, v_count, 64), [&](const auto& range) {
    VertexEstimator estimator(mesh, caster, pools, seeds, reflectance);
    const std::size_t step = estimator.vertices_a_call();
    for (std::size_t i = range.begin(); i < range.end(); i += step)
      estimator.estimate(order.data() + i, std::min(step, range.end() - i), out.batches);
    rays += estimator.rays();
    if (progress) progress->add(double(range.size()), double(estimator.rays()));
  });
  out.rays = rays;
  return out;
}

Eigen::MatrixX3f ground_truth_radiance(const Mesh& mesh, const Environment& environment,
                                       int samples, std::uint64_t seed, Progress* progress,
                                       const Reflectance& reflectance) {
  return std::move(
      ground_truth_estimate(mesh, environment, samples, {seed}, progress, reflectance).batches[0]);
}

}  // namespace prt
