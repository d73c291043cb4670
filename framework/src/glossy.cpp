#include "prt/glossy.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <bit>
#include <cmath>

#include "prt/basis.hpp"
#include "prt/error.hpp"
#include "prt/hemisphere.hpp"
#include "prt/progress.hpp"
#include "prt/sh.hpp"
#include "prt/transport.hpp"

namespace prt {

std::vector<Frame> tangent_frames(const Mesh& mesh) {
  std::vector<Frame> frames(mesh.vertex_count());
  for (std::size_t v = 0; v < frames.size(); ++v) {
    const Eigen::Vector3d n = mesh.normals[v].cast<double>().normalized();
    const Eigen::Vector3d axis =
        std::abs(n.y()) < 0.999 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitX();
    const Eigen::Vector3d t = (axis - axis.dot(n) * n).normalized();
    frames[v].row(0) = t;
    frames[v].row(1) = n.cross(t);
    frames[v].row(2) = n;
  }
  return frames;
}

GlossyChain GlossyChain::make(const Brdf& brdf, const ExitBasis& exit, int light_order,
                              bool least_squares, double cutoff) {
  if (!exit.glossy()) throw Error("glossy transfer needs an exit basis");
  GlossyChain chain{exit, light_order, least_squares,
                    brdf_matrix(brdf, exit.order, exit.kept, light_order)};
  if (!least_squares) return chain;
  // The one SH index the exit basis leaves out, if any (the reduced basis).
  int dropped = -1;
  for (int i = 0, k = 0; i < exit.order * exit.order; ++i) {
    if (k < static_cast<int>(exit.kept.size()) && exit.kept[k] == i)
      ++k;
    else if (dropped < 0)
      dropped = i;
    else
      throw Error("glossy transfer: the exit basis may leave out at most one function");
  }
  const auto exit_ls = hemisphere::least_squares(exit.order, cutoff, dropped);
  const auto light_ls = hemisphere::least_squares(light_order, cutoff);
  chain.matrix = exit_ls.inverse * chain.matrix * light_ls.inverse;
  return chain;
}

TransferSignal glossy_transfer(const Mesh& mesh, const DirectionSet& set,
                               const VisibilityBits& visibility, const Basis& light_basis,
                               const GlossyChain& chain, Progress* progress) {
  const int n_i = light_basis.size(), n_r = chain.exit.rows();
  if (n_i != chain.light_order * chain.light_order || chain.matrix.cols() != n_i)
    throw Error("glossy transfer: the light basis has " + std::to_string(n_i) +
                " functions, the chain expects " + std::to_string(chain.matrix.cols()));
  if (!light_basis.can_rotate())
    throw Error("glossy transfer needs a light basis that rotates (R_p)");
  if (visibility.vertices() != mesh.vertex_count() ||
      visibility.directions() != static_cast<std::size_t>(set.size()))
    throw Error("glossy transfer: visibility does not match the mesh and directions");
  const Eigen::MatrixXd values = light_basis.evaluate(set.directions);    // s x N_i
  const Eigen::MatrixXd projection = light_basis.projection_matrix(set);  // s x N_i
  const std::vector<Frame> frames = tangent_frames(mesh);
  const std::size_t words = VisibilityBits::words_for(set.size());

  TransferSignal out;
  out.kind = "glossy";
  out.exit = chain.exit;
  out.coefficients.resize(static_cast<Eigen::Index>(mesh.vertex_count()), n_r * n_i);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, mesh.vertex_count(), 64), [&](const auto& range) {
        Eigen::MatrixXd visible_values, visible_projection;
        std::vector<std::uint32_t> seen;
        for (std::size_t v = range.begin(); v < range.end(); ++v) {
          seen.clear();
          const std::uint64_t* bits = visibility.words(v);
          for (std::size_t w = 0; w < words; ++w)
            for (std::uint64_t b = bits[w]; b; b &= b - 1)
              seen.push_back(static_cast<std::uint32_t>(64 * w + std::countr_zero(b)));
          visible_values.resize(seen.size(), n_i);
          visible_projection.resize(seen.size(), n_i);
          for (std::size_t j = 0; j < seen.size(); ++j) {
            visible_values.row(j) = values.row(seen[j]);
            visible_projection.row(j) = projection.row(seen[j]);
          }
          // T_p: light coefficients -> coefficients of V(s) L(s) (zero below the horizon).
          const Eigen::MatrixXd transferred = visible_projection.transpose() * visible_values;
          const Eigen::MatrixXd m =
              chain.matrix * (light_basis.rotation_matrix(frames[v]) * transferred);
          out.coefficients.row(static_cast<Eigen::Index>(v)) =
              Eigen::Map<const Eigen::Matrix<double, 1, Eigen::Dynamic>>(
                  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>(m).data(),
                  n_r * n_i)
                  .cast<float>();
        }
        if (progress) progress->add(double(range.size()));
      });
  return out;
}

Eigen::Vector3d upper_hemisphere(Eigen::Vector3d local) {
  // Just above the horizon rather than on it: BRDFs vanish at z = 0, and a
  // vertex seen edge-on should keep its grazing radiance.
  local.z() = std::max(local.z(), 1e-3 * local.norm());
  const double norm = local.norm();
  return norm > 1e-12 ? Eigen::Vector3d(local / norm) : Eigen::Vector3d::UnitZ();
}

std::vector<Eigen::Vector3d> local_view_directions(const Mesh& mesh,
                                                   const std::vector<Frame>& frames,
                                                   const Eigen::Vector3f& eye) {
  std::vector<Eigen::Vector3d> views(mesh.vertex_count());
  for (std::size_t v = 0; v < views.size(); ++v)
    views[v] = upper_hemisphere(frames[v] * (eye - mesh.positions[v]).cast<double>());
  return views;
}

Eigen::MatrixX3f evaluate_exit(const MatrixXfRow& coefficients, const ExitBasis& exit,
                               const std::vector<Eigen::Vector3d>& local_views) {
  const int rows = exit.rows();
  if (coefficients.cols() != 3 * rows ||
      coefficients.rows() != static_cast<Eigen::Index>(local_views.size()))
    throw Error("evaluate_exit: coefficients do not match the exit basis and vertices");
  Eigen::MatrixX3f out(coefficients.rows(), 3);
  tbb::parallel_for(Eigen::Index(0), coefficients.rows(), [&](Eigen::Index p) {
    double y[kMaxExitCoefficients];
    exit.evaluate(local_views[p], y);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int i = 0; i < rows; ++i)
      for (int c = 0; c < 3; ++c) sum[c] += y[i] * coefficients(p, 3 * i + c);
    out.row(p) = sum.cast<float>().transpose();
  });
  return out;
}

}  // namespace prt
