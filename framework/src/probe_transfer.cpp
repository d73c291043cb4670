#include "prt/probe_transfer.hpp"

#include <tbb/parallel_for.h>

#include "prt/error.hpp"
#include "prt/progress.hpp"

namespace prt {

namespace {

constexpr std::size_t kProbesPerTask = 16;

// One probe's visibility over the set (1: the ray escapes) and whether it
// sits inside geometry.
struct ProbeRays {
  Eigen::VectorXd visible;
  bool valid = true;
};

ProbeRays trace_probe(const RayCaster& caster, const Mesh& scene, const Eigen::Vector3f& at,
                      const DirectionSet& set, double invalid_fraction) {
  const std::size_t s = std::size_t(set.size());
  std::vector<float> origins(3 * s), directions(3 * s);
  for (std::size_t d = 0; d < s; ++d)
    for (int a = 0; a < 3; ++a) {
      origins[3 * d + a] = at[a];
      directions[3 * d + a] = float(set.directions(Eigen::Index(d), a));
    }
  std::vector<std::int64_t> triangle(s);
  std::vector<float> u(s), v(s);
  std::vector<std::uint8_t> escaped(s);
  caster.intersect(scene, origins.data(), directions.data(), s, triangle.data(), u.data(), v.data(),
                   escaped.data());
  ProbeRays out;
  out.visible.resize(Eigen::Index(s));
  std::size_t back = 0;
  for (std::size_t d = 0; d < s; ++d) {
    out.visible[Eigen::Index(d)] = escaped[d] ? 1.0 : 0.0;
    back += !escaped[d] && triangle[d] < 0;  // hit, but not a front face
  }
  out.valid = double(back) <= invalid_fraction * double(s);
  return out;
}

}  // namespace

ProbeTransfer probe_transfer(const RayCaster& caster, const Mesh& scene, const ProbeGrid& grid,
                             const DirectionSet& set, const Basis& light_basis,
                             const Basis& incident_basis, double invalid_fraction, bool shadowed,
                             Progress* progress, std::size_t first_probe, std::size_t last_probe) {
  const Eigen::MatrixXd projection = incident_basis.projection_matrix(set);  // s x n_E
  const Eigen::MatrixXd values = light_basis.evaluate(set.directions);       // s x n_B
  const Eigen::Index n = incident_basis.size(), m = light_basis.size();
  last_probe = std::min(last_probe, grid.count());
  first_probe = std::min(first_probe, last_probe);
  const std::size_t probes = last_probe - first_probe;
  ProbeTransfer out;
  out.transfer.kind = "incident";
  out.transfer.exit_rows = int(n);
  out.transfer.coefficients = MatrixXfRow::Zero(Eigen::Index(probes), n * m);
  out.valid.assign(probes, 1);
  const Eigen::MatrixXd unshadowed = projection.transpose() * values;
  tbb::parallel_for(
      std::size_t(0), (probes + kProbesPerTask - 1) / kProbesPerTask, [&](std::size_t task) {
        const std::size_t first = task * kProbesPerTask;
        const std::size_t last = std::min(probes, first + kProbesPerTask);
        for (std::size_t p = first; p < last; ++p) {
          Eigen::MatrixXd t;  // n_E x n_B
          if (shadowed) {
            const ProbeRays rays =
                trace_probe(caster, scene, grid.position(first_probe + p), set, invalid_fraction);
            out.valid[p] = rays.valid;
            if (!rays.valid) continue;
            t = projection.transpose() * (rays.visible.asDiagonal() * values);
          } else {
            t = unshadowed;
          }
          const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> row_major =
              t;
          out.transfer.coefficients.row(Eigen::Index(p)) =
              Eigen::Map<const Eigen::RowVectorXd>(row_major.data(), n * m).cast<float>();
        }
        if (progress)
          progress->add(double(last - first),
                        shadowed ? double(last - first) * double(set.size()) : 0);
      });
  out.rays_cast = shadowed ? std::uint64_t(probes) * std::uint64_t(set.size()) : 0;
  return out;
}

std::vector<Eigen::MatrixX3d> incident_light(const CompressedTransfer& transfer, int incident_size,
                                             const Eigen::MatrixX3d& light) {
  const Eigen::Index n = incident_size, m = light.rows();
  if (transfer.dimension != n * m)
    throw Error("probe transfer of " + std::to_string(transfer.dimension) +
                " coefficients a probe does not map a light of " + std::to_string(m) +
                " coefficients to " + std::to_string(n) + " incident ones");
  std::vector<Eigen::MatrixX3d> incident(std::size_t(transfer.vertices()));
  tbb::parallel_for(Eigen::Index(0), transfer.vertices(), [&](Eigen::Index p) {
    Eigen::RowVectorXf row(n * m);
    transfer.decode_row(p, row);
    const Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> t(
        row.data(), n, m);
    incident[std::size_t(p)] = t.cast<double>() * light;
  });
  return incident;
}

}  // namespace prt
