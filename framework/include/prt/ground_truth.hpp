// The Monte Carlo ground truth that PRT is measured against: no basis, no
// compression, the environment sampled directly with ray-cast visibility.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

#include "prt/mesh.hpp"

namespace prt {

class Progress;

// Cosine-weighted directions about a unit normal: sample(u1, u2) maps the unit
// square to the hemisphere with density cos / pi (Malley's method). Shared by
// the ground truth's direct light and its bounces.
class CosineHemisphere {
 public:
  explicit CosineHemisphere(const Eigen::Vector3d& normal);
  Eigen::Vector3d sample(double u1, double u2) const;
  const Eigen::Vector3d& tangent() const { return tangent_; }
  const Eigen::Vector3d& bitangent() const { return bitangent_; }

 private:
  Eigen::Vector3d normal_, tangent_, bitangent_;
};

// Ground truth: per-vertex exit radiance (v x 3) for albedo 1, by Monte Carlo
// over the environment with ray-cast visibility; no basis involved.
// Samples are stratified, and each stratum's sample is one of a pool of
// candidates drawn (and looked up in the map) once per call (SamplePool):
// under a constant map cosine-weighted directions in each vertex's frame
// (exact on a convex object), under a real map uniform-sphere and
// map-importance directions combined by the balance heuristic. Each vertex
// picks a candidate per stratum from a random stream seeded by the seed and
// the vertex, and traces those above its tangent plane; vertices go along a
// Morton curve, so consecutive ones send rays from nearby origins into the
// same strata. Two vertices share a stratum's sample with probability
// 1 / candidates: their errors are nearly independent and show no pattern.
// For glossy materials `reflectance` (optional) gives pi * rho(in, out) at a
// vertex for a world light direction, which replaces albedo 1.
class Environment;
class RayCaster;
class EnvironmentSampler;
using Reflectance = std::function<double(std::size_t vertex, const Eigen::Vector3d& light)>;

// Independent estimates, one per seed, traced together: each vertex's rays
// of every batch in one call, so each origin's walk down the BVH serves them
// all, over one BVH (built here).
struct GroundTruthEstimate {
  std::vector<Eigen::MatrixX3f> batches;  // v x 3 per seed
  std::uint64_t rays = 0;                 // occlusion rays traced
};
// `occluders`: the scene the rays test, when it is not `mesh` itself (the
// vertices of a moving object against a scene that holds it, or not).
GroundTruthEstimate ground_truth_estimate(const Mesh& mesh, const Environment& environment,
                                          int samples, const std::vector<std::uint64_t>& seeds,
                                          Progress* progress,
                                          const Reflectance& reflectance = nullptr,
                                          const RayCaster* occluders = nullptr);
// One batch's radiance.
Eigen::MatrixX3f ground_truth_radiance(const Mesh& mesh, const Environment& environment,
                                       int samples, std::uint64_t seed, Progress* progress,
                                       const Reflectance& reflectance = nullptr);

// The candidates of every stratum. `local`: directions in each vertex's frame
// (x, y tangent, z normal), each carrying `weighted` = L / N (the cosine
// cancels its density); otherwise world directions, each carrying
// L / (pi (N_sphere p_sphere + N_map p_map)), to be multiplied by the
// vertex's cosine. Entry (stratum, candidate) is at stratum * candidates +
// candidate.
struct SamplePool {
  bool local = false;
  int strata = 0, candidates = 0;
  struct Entry {
    Eigen::Vector3f direction, weighted;  // together: one load from the pool
  };
  std::vector<Entry> entries;
  // The entries vertex v uses, one per stratum, into entries[0, strata).
  void pick(std::uint64_t seed, std::size_t vertex, std::size_t* entries) const;
};
// The pool of a run with `seed`: side^2 strata per strategy (a null sampler:
// the cosine strategy alone, for a constant map), up to 16 candidates each.
SamplePool draw_sample_pool(const Environment& environment, const EnvironmentSampler* sampler,
                            int side, std::uint64_t seed);

}  // namespace prt

namespace prt {

struct Brdf;

// The glossy ground truth's inter-reflected light, independent of any basis
// and of the bake's directions: per vertex `samples` paths (stratified
// cosine-weighted first directions) that hit the mesh and continue for up to
// `bounces` reflections, each hit point q shading with the BRDF in its own
// frame (interpolated normal) toward where the path came from, times the
// bounce albedo. At each hit, the environment's light is gathered by two
// strategies (cosine and the map's importance sampling) combined by the
// balance heuristic. Returns the radiance the bounces add toward each
// vertex's local view (v x 3, albedo 1); the direct light is
// ground_truth_radiance's.
Eigen::MatrixX3f ground_truth_glossy_bounces(const Mesh& mesh, const Environment& environment,
                                             const Brdf& brdf, const Eigen::MatrixXd& local_views,
                                             int bounces, double albedo, int samples,
                                             std::uint64_t seed, Progress* progress);

}  // namespace prt
