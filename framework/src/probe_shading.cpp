#include "prt/probe_shading.hpp"

#include <tbb/parallel_for.h>

#include <atomic>
#include <numeric>

#include "prt/error.hpp"

namespace prt {

Eigen::MatrixXd cosine_lobes(const Basis& basis, const std::vector<Eigen::Vector3f>& normals,
                             const DirectionSet& set) {
  const Eigen::MatrixXd weighted =
      set.weights.asDiagonal() * basis.evaluate(set.directions) / M_PI;  // s x n
  const Eigen::Index v = Eigen::Index(normals.size());
  Eigen::MatrixXd lobes(v, basis.size());
  constexpr Eigen::Index kBlock = 512;
  tbb::parallel_for(Eigen::Index(0), (v + kBlock - 1) / kBlock, [&](Eigen::Index block) {
    const Eigen::Index first = block * kBlock, count = std::min(kBlock, v - first);
    Eigen::MatrixXd cosines(count, set.size());
    for (Eigen::Index i = 0; i < count; ++i) {
      const Eigen::Vector3d n = normals[std::size_t(first + i)].cast<double>();
      cosines.row(i) = (set.directions * n).cwiseMax(0.0).transpose();
    }
    lobes.middleRows(first, count) = cosines * weighted;
  });
  return lobes;
}

namespace {

constexpr Eigen::Index kPointsPerTask = 256;

// Visibility of each corner probe from each point of a task: rays from the
// probes (in free space when valid) to the biased points, stopping just
// short of them, so that a point lying on a surface, or where two meet (a
// wall's foot on the floor), is not hidden by that surface at its own
// ray's end.
std::vector<std::uint8_t> probes_seen(const RayCaster& caster, const ProbeGrid& grid,
                                      const std::vector<Eigen::Vector3f>& from,
                                      const std::vector<std::array<std::uint32_t, 8>>& corners) {
  const std::size_t rays = 8 * from.size();
  std::vector<float> origins(3 * rays), directions(3 * rays), far(rays);
  const float short_of = 4 * caster.offset();
  for (std::size_t i = 0; i < from.size(); ++i)
    for (std::size_t c = 0; c < 8; ++c) {
      const std::size_t r = 8 * i + c;
      const Eigen::Vector3f probe = grid.position(corners[i][c]);
      const Eigen::Vector3f to = from[i] - probe;
      const float length = to.norm();
      const Eigen::Vector3f direction =
          length > 0 ? Eigen::Vector3f(to / length) : Eigen::Vector3f::UnitY();
      for (int a = 0; a < 3; ++a) {
        origins[3 * r + a] = probe[a];
        directions[3 * r + a] = direction[a];
      }
      far[r] = std::max(0.f, length - short_of);
    }
  std::vector<std::uint8_t> seen(rays);
  caster.occluded(origins.data(), directions.data(), rays, seen.data(), far.data());
  return seen;
}

// The points moved along their normals by `bias` (world units), each no
// further than the free space in front of it allows: a point whose move
// would cross a surface (a thin wall, a nearby object) moves half as far,
// then a quarter, else stays. A biased point inside a wall sees no probe.
void move_along_normals(const RayCaster& caster, const Mesh& points, Eigen::Index first, float bias,
                        std::vector<Eigen::Vector3f>& at) {
  std::vector<float> origins(3 * at.size()), directions(3 * at.size()), far(at.size());
  std::vector<std::uint8_t> free(at.size());
  std::vector<float> moved(at.size(), 0.f);
  std::vector<std::size_t> pending(at.size());
  for (std::size_t i = 0; i < at.size(); ++i) pending[i] = i;
  // The rays start one ray offset off the surface, as the bake's do: from
  // the point itself they would hit its own triangles.
  const float offset = caster.offset();
  for (float step = bias; step > bias / 5 && !pending.empty(); step /= 2) {
    for (std::size_t k = 0; k < pending.size(); ++k) {
      const std::size_t i = pending[k];
      const Eigen::Vector3f& n = points.normals[std::size_t(first) + i];
      for (int a = 0; a < 3; ++a) {
        origins[3 * k + a] = at[i][a] + offset * n[a];
        directions[3 * k + a] = n[a];
      }
      far[k] = std::max(0.f, step - offset);
    }
    caster.occluded(origins.data(), directions.data(), pending.size(), free.data(), far.data());
    std::size_t kept = 0;
    for (std::size_t k = 0; k < pending.size(); ++k)
      if (free[k])
        moved[pending[k]] = step;
      else
        pending[kept++] = pending[k];
    pending.resize(kept);
  }
  for (std::size_t i = 0; i < at.size(); ++i)
    at[i] += moved[i] * points.normals[std::size_t(first) + i];
}

}  // namespace

namespace {

// One point's weights over its 8 probes: the trilinear weights of the
// usable ones (`seen`: null without the leak control), renormalised. A
// point that sees none of its valid probes takes the valid ones in front of
// its surface, else every valid one, else (a point on a face of its cell,
// whose corners with weight are all invalid) every valid corner equally
// (`unseen` counts them). Zero weights: no valid probe around.
std::array<float, 8> point_weights(const Mesh& points, std::size_t p, const ProbeGrid& grid,
                                   const std::vector<std::uint8_t>& valid,
                                   const std::array<std::uint32_t, 8>& corner,
                                   const std::array<float, 8>& trilinear, const std::uint8_t* seen,
                                   std::atomic<std::size_t>& unseen) {
  std::array<double, 8> w{};
  double total = 0;
  for (std::size_t c = 0; c < 8; ++c) {
    w[c] = !seen || (valid[corner[c]] && seen[c]) ? trilinear[c] : 0.0;
    total += w[c];
  }
  if (seen && !(total > 0)) {
    // No valid probe in sight (the point's rays start on another surface,
    // e.g. a wall's foot on the floor).
    ++unseen;
    for (int pass = 0; pass < 3 && !(total > 0); ++pass)
      for (std::size_t c = 0; c < 8; ++c) {
        const bool in_front =
            pass > 0 || points.normals[p].dot(grid.position(corner[c]) - points.positions[p]) > 0;
        w[c] = valid[corner[c]] && in_front ? (pass == 2 ? 1.0 : trilinear[c]) : 0.0;
        total += w[c];
      }
  }
  std::array<float, 8> out{};
  for (std::size_t c = 0; c < 8; ++c) out[c] = total > 0 ? float(w[c] / total) : 0.f;
  return out;
}

}  // namespace

ProbeWeights probe_weights(const Mesh& points, const ProbeGrid& grid,
                           const std::vector<std::uint8_t>& valid, const RayCaster* caster,
                           const ProbeLookup& lookup) {
  const Eigen::Index v = Eigen::Index(points.vertex_count());
  if (valid.size() != grid.count())
    throw Error("probe shading: " + std::to_string(grid.count()) + " probes and " +
                std::to_string(valid.size()) + " validity flags");
  const bool control = lookup.interpolation == ProbeInterpolation::visibility;
  if (control && !caster) throw Error("probe shading with leak control needs the scene's rays");
  ProbeWeights out;
  out.probes.resize(std::size_t(v));
  out.weights.resize(std::size_t(v));
  std::atomic<std::size_t> unseen{0}, no_valid{0};
  tbb::parallel_for(
      Eigen::Index(0), (v + kPointsPerTask - 1) / kPointsPerTask, [&](Eigen::Index task) {
        const auto first = std::size_t(task * kPointsPerTask);
        const auto count = std::size_t(std::min(kPointsPerTask, v - Eigen::Index(first)));
        std::vector<Eigen::Vector3f> at(points.positions.begin() + std::ptrdiff_t(first),
                                        points.positions.begin() + std::ptrdiff_t(first + count));
        if (control && lookup.normal_bias > 0)
          move_along_normals(*caster, points, Eigen::Index(first),
                             lookup.normal_bias * grid.spacing, at);
        auto* corners = out.probes.data() + first;
        std::vector<std::array<float, 8>> trilinear(count);
        for (std::size_t i = 0; i < count; ++i) grid.cell(at[i], corners[i], trilinear[i]);
        std::vector<std::uint8_t> seen;
        if (control)
          seen = probes_seen(*caster, grid, at,
                             std::vector<std::array<std::uint32_t, 8>>(corners, corners + count));
        for (std::size_t i = 0; i < count; ++i) {
          auto& weights = out.weights[first + i];
          weights = point_weights(points, first + i, grid, valid, corners[i], trilinear[i],
                                  control ? seen.data() + 8 * i : nullptr, unseen);
          if (!(std::accumulate(weights.begin(), weights.end(), 0.f) > 0)) ++no_valid;
        }
      });
  out.unseen = unseen;
  out.no_valid_probe = no_valid;
  out.rays_cast = control ? std::uint64_t(8) * std::uint64_t(v) : 0;
  return out;
}

Eigen::MatrixX3f shade_with(const ProbeWeights& weights, const Eigen::MatrixXd& lobes,
                            const std::vector<Eigen::MatrixX3d>& incident) {
  const auto v = Eigen::Index(weights.probes.size());
  if (lobes.rows() != v)
    throw Error("probe shading: " + std::to_string(lobes.rows()) + " lobes for " +
                std::to_string(v) + " points");
  for (const auto& e : incident)
    if (e.rows() != lobes.cols())
      throw Error("probe shading: incident light of " + std::to_string(e.rows()) +
                  " coefficients for lobes of " + std::to_string(lobes.cols()));
  Eigen::MatrixX3f radiance(v, 3);
  tbb::parallel_for(Eigen::Index(0), v, [&](Eigen::Index p) {
    Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
    for (std::size_t c = 0; c < 8; ++c) {
      const float w = weights.weights[std::size_t(p)][c];
      if (w > 0) {
        const std::uint32_t probe = weights.probes[std::size_t(p)][c];
        if (probe >= incident.size()) throw Error("probe shading: a probe index out of range");
        sum += double(w) * (lobes.row(p) * incident[probe]);
      }
    }
    radiance.row(p) = sum.cast<float>();
  });
  return radiance;
}

ProbeShading shade_from_probes(const Mesh& points, const ProbeGrid& grid,
                               const std::vector<std::uint8_t>& valid,
                               const std::vector<Eigen::MatrixX3d>& incident,
                               const Eigen::MatrixXd& lobes, const RayCaster* caster,
                               const ProbeLookup& lookup) {
  if (incident.size() != grid.count())
    throw Error("probe shading: " + std::to_string(grid.count()) + " probes and " +
                std::to_string(incident.size()) + " incident lights");
  const ProbeWeights weights = probe_weights(points, grid, valid, caster, lookup);
  ProbeShading out;
  out.radiance = shade_with(weights, lobes, incident);
  out.unseen = weights.unseen;
  out.no_valid_probe = weights.no_valid_probe;
  out.rays_cast = weights.rays_cast;
  return out;
}

}  // namespace prt
