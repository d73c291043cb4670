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

// What every path of one bake's ground truth shares.
struct PathScene {
  const Mesh& mesh;
  const RayCaster& caster;
  const Environment& environment;
  const EnvironmentSampler* sampler;  // null: a constant environment (no map to sample)
  const Brdf& brdf;
  const std::vector<Frame>& frames;
  const Eigen::MatrixXd& local_views;
  double albedo, offset;
  int bounces, side;  // side x side stratified first directions per vertex
};

// One thread's paths: its ray buffers are kept from vertex to vertex.
class GlossyPaths {
 public:
  GlossyPaths(const PathScene& scene)
      : s_(scene),
        n_(scene.side * scene.side),
        paths_(n_),
        origins_(3 * n_),
        directions_(3 * n_),
        u_(n_),
        v_(n_),
        env_origins_(3 * n_),
        env_directions_(3 * n_),
        triangle_(n_),
        escaped_(n_),
        env_escaped_(n_),
        env_weight_(n_),
        env_light_(n_) {}

  // Vertex p's radiance toward its view: the light of n paths after their
  // first bounce (the direct light is the direct transfer's), averaged.
  Eigen::Vector3d radiance(Eigen::Index p, std::uint64_t seed, std::uint64_t& rays) {
    // Seeded per vertex: independent of scheduling.
    std::mt19937_64 rng((seed ^ 0x5851F42D4C957F2Dull) * 0x9E3779B97F4A7C15ull + p);
    std::vector<PathState> live = first_hits(p, rng, rays);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int depth = 1; depth <= s_.bounces && !live.empty(); ++depth)
      live = bounce(std::move(live), depth, rng, sum, rays);
    return sum / n_;
  }

 private:
  // Stratified cosine-weighted first directions from p, traced; the paths
  // whose first segment hit a front face (an escaped one is the direct light's).
  std::vector<PathState> first_hits(Eigen::Index p, std::mt19937_64& rng, std::uint64_t& rays) {
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    const int side = s_.side;
    const Frame& frame = s_.frames[std::size_t(p)];
    const Eigen::Vector3d view = s_.local_views.row(p).transpose();
    const Eigen::Vector3d normal = s_.mesh.normals[p].cast<double>().normalized();
    const CosineHemisphere hemisphere(normal);
    const Eigen::Vector3d origin = s_.mesh.positions[p].cast<double>() + s_.offset * normal;
    for (int k = 0; k < n_; ++k) {
      const double u1 = (k / side + uniform(rng)) / side, u2 = (k % side + uniform(rng)) / side;
      const Eigen::Vector3d d = hemisphere.sample(u1, u2);
      put(origins_, k, origin), put(directions_, k, d);
      paths_[k].direction = d;
      paths_[k].throughput = M_PI * s_.brdf.evaluate(frame * d, view);
    }
    s_.caster.intersect(s_.mesh, origins_.data(), directions_.data(), n_, triangle_.data(),
                        u_.data(), v_.data());
    rays += n_;
    std::vector<PathState> live;
    for (int k = 0; k < n_; ++k)
      if (triangle_[k] >= 0 && paths_[k].throughput > 0)
        live.push_back({paths_[k].direction, paths_[k].throughput, triangle_[k], u_[k], v_[k]});
    return live;
  }

  // One bounce of the live paths: the environment through both strategies
  // (map importance sampling and the cosine continuation, weighted by MIS)
  // into `sum`; returns the paths that hit a front face and go on.
  std::vector<PathState> bounce(std::vector<PathState> live, int depth, std::mt19937_64& rng,
                                Eigen::Vector3d& sum, std::uint64_t& rays) {
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    const std::size_t h = live.size();
    std::vector<HitSurface> surfaces(h);
    for (std::size_t j = 0; j < h; ++j) {
      const HitSurface& hit = surfaces[j] =
          surface_at(s_.mesh, live[j].triangle, live[j].u, live[j].v);
      const Eigen::Vector3d out_local = hit.frame * (-live[j].direction);
      const double throughput = s_.albedo * live[j].throughput;
      const Eigen::Vector3d o = hit.position + s_.offset * hit.normal;
      // Strategy 1: the map's importance sampling.
      env_weight_[j] = 0;
      if (s_.sampler) {
        const auto sample = s_.sampler->sample(uniform(rng), uniform(rng));
        const double cosine = sample.direction.dot(hit.normal);
        if (cosine > 0) {
          const double rho = s_.brdf.evaluate(hit.frame * sample.direction, out_local);
          env_weight_[j] = throughput * rho * cosine / (sample.pdf + cosine / M_PI);
          env_light_[j] = s_.environment.texel_radiance_at(sample.uv).cast<double>();
        }
        put(env_origins_, j, o), put(env_directions_, j, sample.direction);
      }
      // Strategy 2: cosine-weighted; also the path's continuation.
      const Eigen::Vector3d d = CosineHemisphere(hit.normal).sample(uniform(rng), uniform(rng));
      live[j].direction = d;
      live[j].throughput = throughput * M_PI * s_.brdf.evaluate(hit.frame * d, out_local);
      put(origins_, j, o), put(directions_, j, d);
    }
    if (s_.sampler) {
      s_.caster.occluded(env_origins_.data(), env_directions_.data(), h, env_escaped_.data());
      rays += h;
      for (std::size_t j = 0; j < h; ++j)
        if (env_escaped_[j] && env_weight_[j] > 0) sum += env_weight_[j] * env_light_[j];
    }
    s_.caster.intersect(s_.mesh, origins_.data(), directions_.data(), h, triangle_.data(),
                        u_.data(), v_.data(), escaped_.data());
    rays += h;
    std::vector<PathState> continuing;
    for (std::size_t j = 0; j < h; ++j) {
      const PathState& path = live[j];
      if (path.throughput <= 0) continue;
      if (escaped_[j]) {
        const double cosine_pdf = std::max(0.0, path.direction.dot(surfaces[j].normal)) / M_PI;
        const Eigen::Vector2d uv = s_.environment.uv_of(path.direction);
        const double map_pdf = s_.sampler ? s_.sampler->pdf_at(uv) : 0.0;
        const double mis = cosine_pdf > 0 ? cosine_pdf / (cosine_pdf + map_pdf) : 0.0;
        sum += path.throughput * mis * s_.environment.texel_radiance_at(uv).cast<double>();
      } else if (triangle_[j] >= 0 && depth < s_.bounces) {
        continuing.push_back({path.direction, path.throughput, triangle_[j], u_[j], v_[j]});
      }
    }
    return continuing;
  }

  const PathScene& s_;
  const int n_;
  std::vector<PathState> paths_;
  std::vector<float> origins_, directions_, u_, v_, env_origins_, env_directions_;
  std::vector<std::int64_t> triangle_;
  std::vector<std::uint8_t> escaped_, env_escaped_;
  std::vector<double> env_weight_;
  std::vector<Eigen::Vector3d> env_light_;
};

}  // namespace

Eigen::MatrixX3f ground_truth_glossy_bounces(const Mesh& mesh, const Environment& environment,
                                             const Brdf& brdf, const Eigen::MatrixXd& local_views,
                                             int bounces, double albedo, int samples,
                                             std::uint64_t seed, Progress* progress) {
  RayCaster caster(mesh);
  const auto v_count = static_cast<Eigen::Index>(mesh.vertex_count());
  const std::vector<Frame> frames = tangent_frames(mesh);
  std::optional<EnvironmentSampler> sampler;
  if (environment.width() * environment.height() > 1) sampler.emplace(environment);
  const PathScene scene{mesh,
                        caster,
                        environment,
                        sampler ? &*sampler : nullptr,
                        brdf,
                        frames,
                        local_views,
                        albedo,
                        caster.offset(),
                        bounces,
                        std::max(1, static_cast<int>(std::lround(std::sqrt(samples))))};
  Eigen::MatrixX3f out = Eigen::MatrixX3f::Zero(v_count, 3);
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, v_count, 8), [&](const auto& range) {
    GlossyPaths paths(scene);
    std::uint64_t rays = 0;
    for (Eigen::Index p = range.begin(); p < range.end(); ++p)
      out.row(p) = paths.radiance(p, seed, rays).cast<float>().transpose();
    if (progress) progress->add(double(range.size()), double(rays));
  });
  return out;
}

}  // namespace prt
