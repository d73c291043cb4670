#include "prt/ground_truth.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
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

// One task's estimator of the reference at its vertices: stratified cosine
// and map samples combined by the balance heuristic, one occlusion ray each.
// Its buffers are reused vertex after vertex.
class VertexEstimator {
 public:
  VertexEstimator(const Mesh& mesh, const Environment& environment,
                  const EnvironmentSampler* sampler, const RayCaster& caster, int side,
                  const Reflectance& reflectance)
      : mesh_(mesh),
        environment_(environment),
        sampler_(sampler),
        caster_(caster),
        side_(side),
        per_strategy_(side * side),
        n_((sampler ? 2 : 1) * per_strategy_),
        reflectance_(reflectance),
        origins_(3 * n_),
        directions_(3 * n_),
        cosine_pdf_(n_),
        uv_(n_, Eigen::Vector2d::Zero()),
        texel_(n_, 0),
        escaped_(n_) {}

  Eigen::Vector3f radiance(std::size_t v, std::uint64_t seed) {
    draw(v, seed);
    caster_.occluded(origins_.data(), directions_.data(), n_, escaped_.data());
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int k = 0; k < n_; ++k) {
      if (!escaped_[k] || cosine_pdf_[k] <= 0) continue;
      const Eigen::Vector3d d(directions_[3 * k], directions_[3 * k + 1], directions_[3 * k + 2]);
      const double map_pdf = sampler_ ? sampler_->density(texel_[k]) : 0.0;
      // f = L V cos / pi = L cosine_pdf (albedo 1); balance heuristic:
      // f / (N (p_cosine + p_map)).
      double weight = cosine_pdf_[k] / (per_strategy_ * (cosine_pdf_[k] + map_pdf));
      if (reflectance_) weight *= reflectance_(v, d);  // pi rho replaces albedo 1
      sum += weight * environment_.texel_radiance_at(uv_[k]).cast<double>();
    }
    return sum.cast<float>();
  }

 private:
  // Every sample first, its texel's density and radiance requested from
  // memory (random texels of a large map: the loads would stall one at a
  // time); they arrive while the rays are traced. One map lookup per
  // sample, for its density and its texel.
  void draw(std::size_t v, std::uint64_t seed) {
    // Seeded per vertex, so results do not depend on scheduling.
    std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + v);
    std::uniform_real_distribution<double> jitter(0.0, 1.0);
    const Eigen::Vector3d nrm = mesh_.normals[v].cast<double>();
    const CosineHemisphere hemisphere(nrm);
    const Eigen::Vector3f o = mesh_.positions[v] + caster_.offset() * mesh_.normals[v];
    const Eigen::Index width = environment_.width(), height = environment_.height();
    for (int k = 0; k < n_; ++k) {
      // Stratified in [0,1)^2 within each strategy.
      const int stratum = k % per_strategy_;
      const double u1 = (stratum / side_ + jitter(rng)) / side_;
      const double u2 = (stratum % side_ + jitter(rng)) / side_;
      Eigen::Vector3d d;
      if (k < per_strategy_) {  // cosine-weighted hemisphere
        d = hemisphere.sample(u1, u2);
        if (sampler_) uv_[k] = environment_.uv_of(d), texel_[k] = sampler_->texel_at(uv_[k]);
      } else {
        const EnvironmentSampler::Drawn drawn = sampler_->draw(u1, u2);
        d = drawn.direction, texel_[k] = drawn.texel;
        uv_[k] = {(drawn.texel % width + 0.5) / width, (drawn.texel / width + 0.5) / height};
      }
      if (sampler_) {
        sampler_->prefetch(texel_[k]);
        __builtin_prefetch(environment_.pixels().data() + 3 * texel_[k]);
      }
      cosine_pdf_[k] = std::max(0.0, d.dot(nrm)) / M_PI;
      for (int c = 0; c < 3; ++c) origins_[3 * k + c] = o[c], directions_[3 * k + c] = float(d[c]);
    }
  }

  const Mesh& mesh_;
  const Environment& environment_;
  const EnvironmentSampler* sampler_;  // null: a constant map (the cosine alone)
  const RayCaster& caster_;
  int side_, per_strategy_, n_;
  const Reflectance& reflectance_;
  std::vector<float> origins_, directions_;
  std::vector<double> cosine_pdf_;
  std::vector<Eigen::Vector2d> uv_;
  std::vector<Eigen::Index> texel_;
  std::vector<std::uint8_t> escaped_;
};

}  // namespace

Eigen::MatrixX3f ground_truth_radiance(const Mesh& mesh, const Environment& environment,
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
  const int n = strategies * side * side;
  Eigen::MatrixX3f radiance(static_cast<Eigen::Index>(v_count), 3);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, v_count, 16), [&](const auto& range) {
    VertexEstimator estimator(mesh, environment, sampler ? &*sampler : nullptr, caster, side,
                              reflectance);
    for (std::size_t v = range.begin(); v < range.end(); ++v)
      radiance.row(static_cast<Eigen::Index>(v)) = estimator.radiance(v, seed).transpose();
    if (progress) progress->add(static_cast<double>(range.size()), double(range.size()) * n);
  });
  return radiance;
}

}  // namespace prt
