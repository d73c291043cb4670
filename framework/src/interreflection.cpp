#include "prt/interreflection.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "prt/error.hpp"
#include "prt/ground_truth.hpp"
#include "prt/progress.hpp"

namespace prt {

namespace {

// previous at the hit point, interpolated over the hit triangle.
template <class Rows>
auto at_hit(const Mesh& mesh, const Rows& previous, std::uint32_t triangle, float u, float v) {
  const auto& t = mesh.triangles[triangle];
  return ((1.f - u - v) * previous.row(t[0]) + u * previous.row(t[1]) + v * previous.row(t[2]))
      .eval();
}

}  // namespace

MatrixXfRow gather_bounce(const Mesh& mesh, const DirectionSet& set, const HitLists& hits,
                          const MatrixXfRow& previous, double albedo, std::size_t first,
                          std::size_t last) {
  if (hits.size() != mesh.vertex_count() ||
      previous.rows() != static_cast<Eigen::Index>(mesh.vertex_count()))
    throw Error("gather_bounce: hit lists and transfer do not match the mesh");
  last = std::min(last, mesh.vertex_count());
  first = std::min(first, last);
  MatrixXfRow next(Eigen::Index(last - first), previous.cols());
  tbb::parallel_for(Eigen::Index(first), Eigen::Index(last), [&](Eigen::Index p) {
    Eigen::RowVectorXd sum = Eigen::RowVectorXd::Zero(previous.cols());
    const Eigen::Vector3d n = mesh.normals[p].cast<double>();
    for (const SurfaceHit& h : hits[p]) {
      const double weight =
          set.weights[h.direction] * std::max(0.0, n.dot(set.directions.row(h.direction))) / M_PI;
      // The hit point's transfer, interpolated over its triangle (no temporaries).
      const auto& t = mesh.triangles[h.triangle];
      const double b[3] = {1.0 - h.u - h.v, h.u, h.v};
      for (int c = 0; c < 3; ++c) sum += (weight * b[c]) * previous.row(t[c]).cast<double>();
    }
    next.row(p - Eigen::Index(first)) = (albedo * sum).cast<float>();
  });
  return next;
}

BounceFunction diffuse_bounce(const Mesh& mesh, const DirectionSet& set, const HitLists& hits,
                              double albedo) {
  if (!(albedo >= 0 && albedo <= 1))
    throw Error("inter-reflection needs an albedo in [0, 1]; got " + std::to_string(albedo));
  return [&mesh, &set, &hits, albedo](const MatrixXfRow& previous, std::size_t first,
                                      std::size_t last) {
    return gather_bounce(mesh, set, hits, previous, albedo, first, last);
  };
}

Eigen::MatrixX3f ground_truth_bounces(const Mesh& mesh, const Eigen::MatrixX3f& direct, int bounces,
                                      double albedo, int samples, std::uint64_t seed,
                                      Progress* progress) {
  RayCaster caster(mesh);
  const auto v_count = static_cast<Eigen::Index>(mesh.vertex_count());
  const int side = std::max(1, static_cast<int>(std::lround(std::sqrt(samples))));
  const int n = side * side;
  Eigen::MatrixX3f total = direct, previous = direct;
  for (int b = 0; b < bounces; ++b) {
    Eigen::MatrixX3f next(v_count, 3);
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, v_count, 16), [&](const auto& range) {
      std::vector<float> origins(3 * n), directions(3 * n), u(n), v(n);
      std::vector<std::int64_t> triangle(n);
      for (Eigen::Index p = range.begin(); p < range.end(); ++p) {
        // Seeded per vertex and bounce: independent of scheduling.
        std::mt19937_64 rng((seed + 1000003ull * (b + 1)) * 0x9E3779B97F4A7C15ull + p);
        std::uniform_real_distribution<double> jitter(0.0, 1.0);
        const CosineHemisphere hemisphere(mesh.normals[p].cast<double>());
        const Eigen::Vector3f o = mesh.positions[p] + caster.offset() * mesh.normals[p];
        for (int k = 0; k < n; ++k) {  // stratified cosine-weighted directions
          const double u1 = (k / side + jitter(rng)) / side, u2 = (k % side + jitter(rng)) / side;
          const Eigen::Vector3d d = hemisphere.sample(u1, u2);
          for (int c = 0; c < 3; ++c)
            origins[3 * k + c] = o[c], directions[3 * k + c] = float(d[c]);
        }
        caster.intersect(mesh, origins.data(), directions.data(), n, triangle.data(), u.data(),
                         v.data());
        // Cosine-weighted samples: int L cos / pi = mean of L.
        Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
        for (int k = 0; k < n; ++k)
          if (triangle[k] >= 0)
            sum += at_hit(mesh, previous, std::uint32_t(triangle[k]), u[k], v[k]).cast<double>();
        next.row(p) = (albedo * sum / n).cast<float>();
      }
      if (progress) progress->add(double(range.size()), double(range.size()) * n);
    });
    total += next;
    previous = next;
  }
  return total;
}

}  // namespace prt
