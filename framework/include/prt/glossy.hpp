// Glossy transfer (Sloan 2003 §3, §6) for any light basis and any exit basis
// (DESIGN §3). Per vertex p the N_r x N_i matrix
//   M_p = sum_s E(F_p s) b(s)^T V_p(s) w_s
// maps light coefficients l (light L(s) = b(s) . l, b: the sphere basis) to
// the coefficients of exit radiance in a hemisphere basis over the vertex's
// local frame F_p. E, the BRDF-convolved exit basis, is E(w) = G y_M(w):
//   G = P_exit^T F A_M^-1
// with F(v, j) = int_H rho(s, v) y_j(s) s_z ds at the nodes v of a Gauss
// hemisphere rule, P_exit the exit plug-in's projection on that rule, and
// A_M^-1 the least-squares inverse of SH of the incident order M over the
// hemisphere (the BRDF band-limited in its incident direction, as Sloan's
// A_r^-1 B A_i^-1 with an SH light). With SH light of order M and the "hsh"
// exit basis, M_p equals Sloan's chain exactly.
//
// y_M(F_p s) is formed one of two ways: by rotating the vertex's sum
// sum_s y_M(s) b(s)^T V_p(s) w_s with the SH rotation R_M(F_p) (the fast
// path), or by evaluating y_M at every local direction (the general method,
// kept to check the fast one). Neither needs the light basis to rotate.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "prt/brdf.hpp"
#include "prt/direction_set.hpp"
#include "prt/frame.hpp"
#include "prt/mesh.hpp"
#include "prt/transfer.hpp"

namespace prt {

class Basis;
class Progress;
class VisibilityBits;

constexpr int kMaxIncidentOrder = 12;

struct GlossyOperator {
  int incident_order = 0;    // M
  Eigen::MatrixXd matrix;    // G: N_r x M^2
  Eigen::VectorXd constant;  // exit coefficients of the constant function 1 (N_r)

  int rows() const { return static_cast<int>(matrix.rows()); }
  // `exit_basis` must be a hemisphere basis; `least_squares` false drops A_M^-1
  // (the zero-hemisphere projection of Sloan's Fig. 7).
  static GlossyOperator make(const Brdf& brdf, const Basis& exit_basis, int incident_order,
                             bool least_squares, double cutoff, int resolution = 48);
};

enum class GlossyMethod { rotate_sh, evaluate };

// M_p for every vertex from stored visibility (directions above the tangent
// plane whose rays escape), as rows of N_r x N_i, row-major. `visibility`
// holds the vertices from `first_vertex` on (a slab); `frames` all of them.
TransferSignal glossy_transfer(const Mesh& mesh, const DirectionSet& directions,
                               const VisibilityBits& visibility, const Basis& light_basis,
                               const GlossyOperator& glossy, const std::vector<Frame>& frames,
                               GlossyMethod method, Progress* progress,
                               std::size_t first_vertex = 0);

// The exit basis at each vertex's local view direction (v x N_r).
MatrixXfRow exit_values(const Basis& exit_basis, const Eigen::MatrixXd& local_views);

}  // namespace prt
