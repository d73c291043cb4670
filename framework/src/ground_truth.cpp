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
  const int per_strategy = side * side, n = strategies * per_strategy;
  Eigen::MatrixX3f radiance(static_cast<Eigen::Index>(v_count), 3);
  const float* pixels = environment.pixels().data();
  const Eigen::Index width = environment.width(), height = environment.height();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, v_count, 16), [&](const auto& range) {
    std::vector<float> origins(3 * n), directions(3 * n);
    std::vector<double> cosine_pdf(n);
    // One map lookup per sample, for its density and its texel.
    std::vector<Eigen::Vector2d> uv(n, Eigen::Vector2d::Zero());
    std::vector<Eigen::Index> texel(n, 0);
    std::vector<std::uint8_t> escaped(n);
    for (std::size_t v = range.begin(); v < range.end(); ++v) {
      // Seeded per vertex, so results do not depend on scheduling.
      std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + v);
      std::uniform_real_distribution<double> jitter(0.0, 1.0);
      const Eigen::Vector3d nrm = mesh.normals[v].cast<double>();
      const CosineHemisphere hemisphere(nrm);
      const Eigen::Vector3f o = mesh.positions[v] + caster.offset() * mesh.normals[v];
      // Every sample first, its texel's density and radiance requested from
      // memory (random texels of a large map: the loads would stall one at
      // a time); they arrive while the rays are traced.
      for (int k = 0; k < n; ++k) {
        // Stratified in [0,1)^2 within each strategy.
        const int stratum = k % per_strategy;
        const double u1 = (stratum / side + jitter(rng)) / side;
        const double u2 = (stratum % side + jitter(rng)) / side;
        Eigen::Vector3d d;
        if (k < per_strategy) {  // cosine-weighted hemisphere
          d = hemisphere.sample(u1, u2);
          if (use_map) uv[k] = environment.uv_of(d), texel[k] = sampler->texel_at(uv[k]);
        } else {
          const EnvironmentSampler::Drawn drawn = sampler->draw(u1, u2);
          d = drawn.direction, texel[k] = drawn.texel;
          uv[k] = {(drawn.texel % width + 0.5) / width, (drawn.texel / width + 0.5) / height};
        }
        if (use_map) {
          sampler->prefetch(texel[k]);
          __builtin_prefetch(pixels + 3 * texel[k]);
        }
        cosine_pdf[k] = std::max(0.0, d.dot(nrm)) / M_PI;
        for (int c = 0; c < 3; ++c) origins[3 * k + c] = o[c], directions[3 * k + c] = float(d[c]);
      }
      caster.occluded(origins.data(), directions.data(), n, escaped.data());
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int k = 0; k < n; ++k) {
        if (!escaped[k] || cosine_pdf[k] <= 0) continue;
        const Eigen::Vector3d d(directions[3 * k], directions[3 * k + 1], directions[3 * k + 2]);
        const double map_pdf = use_map ? sampler->density(texel[k]) : 0.0;
        // f = L V cos / pi = L cosine_pdf (albedo 1); balance heuristic:
        // f / (N (p_cosine + p_map)).
        double weight = cosine_pdf[k] / (per_strategy * (cosine_pdf[k] + map_pdf));
        if (reflectance) weight *= reflectance(v, d);  // pi rho replaces albedo 1
        sum += weight * environment.texel_radiance_at(uv[k]).cast<double>();
      }
      radiance.row(static_cast<Eigen::Index>(v)) = sum.cast<float>().transpose();
    }
    if (progress) progress->add(static_cast<double>(range.size()), double(range.size()) * n);
  });
  return radiance;
}

}  // namespace prt
