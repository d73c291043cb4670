#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>

#include "prt/brdf.hpp"
#include "prt/environment.hpp"
#include "prt/environment_sampler.hpp"
#include "prt/frame.hpp"
#include "prt/ground_truth.hpp"
#include "prt/progress.hpp"
#include "prt/transport.hpp"

namespace prt {

namespace {

// A path's state between two segments.
struct PathState {
  Eigen::Vector3d direction;  // of the segment that hit
  double throughput = 0;
  std::int64_t triangle = -1;  // the front face hit
  float u = 0, v = 0;
};

// The surface at a hit: interpolated position and normal, and its frame.
struct HitSurface {
  Eigen::Vector3d position, normal;
  Frame frame;
};

HitSurface surface_at(const Mesh& mesh, std::int64_t triangle, float u, float v) {
  const auto& t = mesh.triangles[std::size_t(triangle)];
  const double b[3] = {1.0 - u - v, u, v};
  HitSurface s{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Frame()};
  for (int c = 0; c < 3; ++c) {
    s.position += b[c] * mesh.positions[t[c]].cast<double>();
    s.normal += b[c] * mesh.normals[t[c]].cast<double>();
  }
  s.normal.normalize();
  s.frame = tangent_frame(s.normal);
  return s;
}

void put(std::vector<float>& array, std::size_t k, const Eigen::Vector3d& value) {
  for (int c = 0; c < 3; ++c) array[3 * k + c] = float(value[c]);
}

}  // namespace

Eigen::MatrixX3f ground_truth_glossy_bounces(const Mesh& mesh, const Environment& environment,
                                             const Brdf& brdf, const Eigen::MatrixXd& local_views,
                                             int bounces, double albedo, int samples,
                                             std::uint64_t seed, Progress* progress) {
  RayCaster caster(mesh);
  const auto v_count = static_cast<Eigen::Index>(mesh.vertex_count());
  const std::vector<Frame> frames = tangent_frames(mesh);
  const bool use_map = environment.width() * environment.height() > 1;
  std::optional<EnvironmentSampler> sampler;
  if (use_map) sampler.emplace(environment);
  const int side = std::max(1, static_cast<int>(std::lround(std::sqrt(samples))));
  const int n = side * side;
  const double offset = caster.offset();
  Eigen::MatrixX3f out = Eigen::MatrixX3f::Zero(v_count, 3);
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, v_count, 8), [&](const auto& range) {
    std::vector<PathState> paths(n);
    std::vector<float> origins(3 * n), directions(3 * n), u(n), v(n), env_origins(3 * n),
        env_directions(3 * n);
    std::vector<std::int64_t> triangle(n);
    std::vector<std::uint8_t> escaped(n), env_escaped(n);
    std::vector<double> env_weight(n);
    std::vector<Eigen::Vector3d> env_light(n);
    std::uint64_t rays = 0;
    for (Eigen::Index p = range.begin(); p < range.end(); ++p) {
      // Seeded per vertex: independent of scheduling.
      std::mt19937_64 rng((seed ^ 0x5851F42D4C957F2Dull) * 0x9E3779B97F4A7C15ull + p);
      std::uniform_real_distribution<double> uniform(0.0, 1.0);
      const Frame& frame = frames[std::size_t(p)];
      const Eigen::Vector3d view = local_views.row(p).transpose();
      const Eigen::Vector3d normal = mesh.normals[p].cast<double>().normalized();
      const CosineHemisphere hemisphere(normal);
      const Eigen::Vector3d origin = mesh.positions[p].cast<double>() + offset * normal;
      for (int k = 0; k < n; ++k) {  // stratified cosine-weighted first directions
        const double u1 = (k / side + uniform(rng)) / side, u2 = (k % side + uniform(rng)) / side;
        const Eigen::Vector3d d = hemisphere.sample(u1, u2);
        put(origins, k, origin), put(directions, k, d);
        paths[k].direction = d;
        paths[k].throughput = M_PI * brdf.evaluate(frame * d, view);
      }
      caster.intersect(mesh, origins.data(), directions.data(), n, triangle.data(), u.data(),
                       v.data());
      rays += n;
      std::vector<PathState> live;  // paths whose last segment hit a front face
      for (int k = 0; k < n; ++k)
        if (triangle[k] >= 0 && paths[k].throughput > 0)  // escaped: the direct light's
          live.push_back({paths[k].direction, paths[k].throughput, triangle[k], u[k], v[k]});
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int depth = 1; depth <= bounces && !live.empty(); ++depth) {
        const std::size_t h = live.size();
        std::vector<HitSurface> surfaces(h);
        for (std::size_t j = 0; j < h; ++j) {
          const HitSurface& s = surfaces[j] =
              surface_at(mesh, live[j].triangle, live[j].u, live[j].v);
          const Eigen::Vector3d out_local = s.frame * (-live[j].direction);
          const double throughput = albedo * live[j].throughput;
          const Eigen::Vector3d o = s.position + offset * s.normal;
          // Strategy 1: the map's importance sampling.
          env_weight[j] = 0;
          if (use_map) {
            const auto sample = sampler->sample(uniform(rng), uniform(rng));
            const double cosine = sample.direction.dot(s.normal);
            if (cosine > 0) {
              const double rho = brdf.evaluate(s.frame * sample.direction, out_local);
              env_weight[j] = throughput * rho * cosine / (sample.pdf + cosine / M_PI);
              env_light[j] = environment.texel_radiance(sample.direction).cast<double>();
            }
            put(env_origins, j, o), put(env_directions, j, sample.direction);
          }
          // Strategy 2: cosine-weighted; also the path's continuation.
          const Eigen::Vector3d d = CosineHemisphere(s.normal).sample(uniform(rng), uniform(rng));
          live[j].direction = d;
          live[j].throughput = throughput * M_PI * brdf.evaluate(s.frame * d, out_local);
          put(origins, j, o), put(directions, j, d);
        }
        if (use_map) {
          caster.occluded(env_origins.data(), env_directions.data(), h, env_escaped.data());
          rays += h;
          for (std::size_t j = 0; j < h; ++j)
            if (env_escaped[j] && env_weight[j] > 0) sum += env_weight[j] * env_light[j];
        }
        caster.intersect(mesh, origins.data(), directions.data(), h, triangle.data(), u.data(),
                         v.data(), escaped.data());
        rays += h;
        std::vector<PathState> continuing;
        for (std::size_t j = 0; j < h; ++j) {
          const PathState& path = live[j];
          if (path.throughput <= 0) continue;
          if (escaped[j]) {
            const double cosine_pdf = std::max(0.0, path.direction.dot(surfaces[j].normal)) / M_PI;
            const double map_pdf = use_map ? sampler->pdf(path.direction) : 0.0;
            const double mis = cosine_pdf > 0 ? cosine_pdf / (cosine_pdf + map_pdf) : 0.0;
            sum +=
                path.throughput * mis * environment.texel_radiance(path.direction).cast<double>();
          } else if (triangle[j] >= 0 && depth < bounces) {
            continuing.push_back({path.direction, path.throughput, triangle[j], u[j], v[j]});
          }
        }
        live = std::move(continuing);
      }
      out.row(p) = (sum / n).cast<float>().transpose();
    }
    if (progress) progress->add(double(range.size()), double(rays));
  });
  return out;
}

}  // namespace prt
