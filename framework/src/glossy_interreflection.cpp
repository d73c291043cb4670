#include "prt/glossy_interreflection.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "prt/error.hpp"
#include "prt/progress.hpp"
#include "prt/sh.hpp"
#include "prt/sh_rotation.hpp"

namespace prt {

MatrixXfRow glossy_bounce(const Mesh& mesh, const DirectionSet& set, const HitLists& hits,
                          const MatrixXfRow& previous, const Basis& exit_basis,
                          const GlossyOperator& glossy, int light_size,
                          const std::vector<Frame>& frames, double albedo, std::size_t first,
                          std::size_t last) {
  const int n_r = glossy.rows(), n_i = light_size, order = glossy.incident_order;
  const auto v_count = static_cast<Eigen::Index>(mesh.vertex_count());
  if (hits.size() != mesh.vertex_count() || previous.rows() != v_count ||
      previous.cols() != Eigen::Index(n_r) * n_i || frames.size() != mesh.vertex_count() ||
      exit_basis.size() != n_r)
    throw Error("glossy inter-reflection: hits, frames or transfer do not match the mesh (" +
                std::to_string(previous.cols()) + " columns for " + std::to_string(n_r) + " x " +
                std::to_string(n_i) + ")");
  const Eigen::MatrixXd incident = sh::evaluate(order, set.directions);  // s x M^2
  using RowMatrixF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  last = std::min(last, mesh.vertex_count());
  first = std::min(first, last);
  MatrixXfRow next(Eigen::Index(last - first), previous.cols());
  tbb::parallel_for(
      tbb::blocked_range<Eigen::Index>(Eigen::Index(first), Eigen::Index(last), 32),
      [&](const auto& range) {
        Eigen::MatrixXd exit_directions, arriving, hit_incident, gathered, rotated;
        Eigen::RowVectorXf row(n_i);
        for (Eigen::Index p = range.begin(); p < range.end(); ++p) {
          const auto& list = hits[std::size_t(p)];
          const auto h = static_cast<Eigen::Index>(list.size());
          // Each corner's local direction back toward p.
          exit_directions.resize(3 * h, 3);
          Eigen::VectorXd corner_weight(3 * h);
          for (Eigen::Index j = 0; j < h; ++j) {
            const SurfaceHit& hit = list[std::size_t(j)];
            const Eigen::Vector3d back = -set.directions.row(hit.direction).transpose();
            const auto& t = mesh.triangles[hit.triangle];
            const double beta[3] = {1.0 - hit.u - hit.v, hit.u, hit.v};
            for (int c = 0; c < 3; ++c) {
              const Eigen::Vector3d local = frames[t[c]] * back;
              const bool above = local.z() > 0;
              exit_directions.row(3 * j + c) = above ? local : Eigen::Vector3d::UnitZ();
              corner_weight[3 * j + c] = above ? beta[c] : 0.0;
            }
          }
          const Eigen::MatrixXd exit_values =
              h ? exit_basis.evaluate(exit_directions) : Eigen::MatrixXd(0, n_r);
          // r(s_j): radiance arriving along s_j per light coefficient, times w_j.
          arriving.setZero(h, n_i);
          for (Eigen::Index j = 0; j < h; ++j) {
            const SurfaceHit& hit = list[std::size_t(j)];
            const auto& t = mesh.triangles[hit.triangle];
            row.setZero();
            for (int c = 0; c < 3; ++c) {
              const double weight = corner_weight[3 * j + c];
              if (weight == 0) continue;
              const Eigen::Map<const RowMatrixF> m(previous.row(t[c]).data(), n_r, n_i);
              row.noalias() += (weight * exit_values.row(3 * j + c)).cast<float>() * m;
            }
            arriving.row(j) = set.weights[hit.direction] * row.cast<double>();
          }
          hit_incident.resize(h, incident.cols());
          for (Eigen::Index j = 0; j < h; ++j)
            hit_incident.row(j) = incident.row(list[std::size_t(j)].direction);
          gathered.noalias() = hit_incident.transpose() * arriving;
          rotated.resize(gathered.rows(), gathered.cols());
          sh::Rotation(order, frames[std::size_t(p)]).apply(gathered, rotated);
          const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> m =
              albedo * (glossy.matrix * rotated);
          next.row(p - Eigen::Index(first)) =
              Eigen::Map<const Eigen::RowVectorXd>(m.data(), m.size()).cast<float>();
        }
      });
  return next;
}

BounceFunction glossy_bounce_function(const Mesh& mesh, const DirectionSet& set,
                                      const HitLists& hits, const Basis& exit_basis,
                                      const GlossyOperator& glossy, int light_size,
                                      const std::vector<Frame>& frames, double albedo) {
  if (!(albedo >= 0 && albedo <= 1))
    throw Error("inter-reflection needs an albedo in [0, 1]; got " + std::to_string(albedo));
  return [&mesh, &set, &hits, &exit_basis, &glossy, light_size, &frames, albedo](
             const MatrixXfRow& previous, std::size_t first, std::size_t last) {
    return glossy_bounce(mesh, set, hits, previous, exit_basis, glossy, light_size, frames, albedo,
                         first, last);
  };
}

}  // namespace prt
