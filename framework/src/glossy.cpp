#include "prt/glossy.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <bit>
#include <cmath>

#include "prt/basis.hpp"
#include "prt/error.hpp"
#include "prt/hemisphere.hpp"
#include "prt/progress.hpp"
#include "prt/sh.hpp"
#include "prt/sh_rotation.hpp"
#include "prt/transport.hpp"

namespace prt {

GlossyOperator GlossyOperator::make(const Brdf& brdf, const Basis& exit_basis, int incident_order,
                                    bool least_squares, double cutoff, int resolution) {
  if (exit_basis.domain() != Domain::hemisphere)
    throw Error("glossy transfer: the exit basis must be a hemisphere basis");
  if (incident_order < 1 || incident_order > kMaxIncidentOrder)
    throw Error("glossy transfer: incident order " + std::to_string(incident_order) +
                " is outside [1, " + std::to_string(kMaxIncidentOrder) + "]");
  const DirectionSet h = hemisphere::upper_quadrature(resolution);
  const Eigen::MatrixXd projection = exit_basis.projection_matrix(h);  // q x N_r
  if (projection.rows() != h.size() || projection.cols() != exit_basis.size() ||
      !projection.allFinite())
    throw Error(
        "glossy transfer: the exit basis gave a projection matrix of the wrong shape or "
        "with NaN/Inf values");
  GlossyOperator op;
  op.incident_order = incident_order;
  op.matrix = projection.transpose() *
              brdf_incident_integrals(brdf, h.directions, incident_order, resolution);
  if (least_squares) op.matrix *= hemisphere::least_squares(incident_order, cutoff).inverse;
  op.constant = projection.colwise().sum().transpose();
  return op;
}

namespace {

// Directions whose bit is set in a vertex's visibility.
void visible_directions(const VisibilityBits& visibility, std::size_t vertex, std::size_t words,
                        std::vector<std::uint32_t>& seen) {
  seen.clear();
  const std::uint64_t* bits = visibility.words(vertex);
  for (std::size_t w = 0; w < words; ++w)
    for (std::uint64_t b = bits[w]; b; b &= b - 1)
      seen.push_back(static_cast<std::uint32_t>(64 * w + std::countr_zero(b)));
}

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

}  // namespace

TransferSignal glossy_transfer(const Mesh& mesh, const DirectionSet& set,
                               const VisibilityBits& visibility, const Basis& light_basis,
                               const GlossyOperator& glossy, const std::vector<Frame>& frames,
                               GlossyMethod method, Progress* progress, std::size_t first_vertex) {
  const int n_i = light_basis.size(), n_r = glossy.rows(), order = glossy.incident_order;
  if (light_basis.domain() != Domain::sphere)
    throw Error("glossy transfer: the light basis must be a sphere basis");
  const std::size_t count = visibility.vertices();
  if (first_vertex + count > mesh.vertex_count() ||
      visibility.directions() != static_cast<std::size_t>(set.size()) ||
      frames.size() != mesh.vertex_count())
    throw Error("glossy transfer: visibility or frames do not match the mesh and directions");
  // The light basis's projection at each direction: b(s)^T w_s, through the
  // dual basis G^-1 when the basis is not orthonormal, so that M holds
  // least-squares coefficients of the light side as a diffuse row does (the
  // relight applies G to the light: M G l, prt/basis_metric.hpp).
  const Eigen::MatrixXd light =
      light_basis.orthonormal()
          ? Eigen::MatrixXd(set.weights.asDiagonal() * light_basis.evaluate(set.directions))
          : light_basis.projection_matrix(set);
  const Eigen::MatrixXd incident = sh::evaluate(order, set.directions);  // s x M^2
  const std::size_t words = VisibilityBits::words_for(set.size());

  TransferSignal out;
  out.kind = "glossy";
  out.exit_rows = n_r;
  out.coefficients.resize(static_cast<Eigen::Index>(count), n_r * n_i);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 64), [&](const auto& range) {
    Eigen::MatrixXd visible_light, visible_incident, projected, rotated;
    std::vector<std::uint32_t> seen;
    for (std::size_t row = range.begin(); row < range.end(); ++row) {
      const std::size_t v = first_vertex + row;
      visible_directions(visibility, row, words, seen);
      const auto count = static_cast<Eigen::Index>(seen.size());
      visible_light.resize(count, n_i);
      for (Eigen::Index j = 0; j < count; ++j) visible_light.row(j) = light.row(seen[j]);
      RowMatrix m(n_r, n_i);
      if (method == GlossyMethod::rotate_sh) {
        visible_incident.resize(count, incident.cols());
        for (Eigen::Index j = 0; j < count; ++j) visible_incident.row(j) = incident.row(seen[j]);
        // Block-diagonal rotation applied band by band (no dense M^2 x M^2).
        projected.noalias() = visible_incident.transpose() * visible_light;
        rotated.resize(projected.rows(), projected.cols());
        sh::Rotation(order, frames[v]).apply(projected, rotated);
        m.noalias() = glossy.matrix * rotated;
      } else {
        Directions local(count, 3);
        for (Eigen::Index j = 0; j < count; ++j)
          local.row(j) = (frames[v] * set.directions.row(seen[j]).transpose()).transpose();
        m.noalias() = (glossy.matrix * sh::evaluate(order, local).transpose()) * visible_light;
      }
      out.coefficients.row(static_cast<Eigen::Index>(row)) =
          Eigen::Map<const Eigen::RowVectorXd>(m.data(), n_r * n_i).cast<float>();
    }
    if (progress) progress->add(double(range.size()));
  });
  return out;
}

MatrixXfRow exit_values(const Basis& exit_basis, const Eigen::MatrixXd& local_views) {
  const Eigen::MatrixXd values = exit_basis.evaluate(local_views);
  if (values.rows() != local_views.rows() || values.cols() != exit_basis.size() ||
      !values.allFinite())
    throw Error("exit basis: evaluate gave a matrix of the wrong shape or with NaN/Inf values");
  return values.cast<float>();
}

}  // namespace prt
