// Glossy transfer (Sloan 2003 §3, §6): per vertex the exiting-radiance matrix
//   M_p = A_r^-1 B A_i^-1 R_p T_p
// T_p maps the global light (SH, N_i) to transferred incident radiance
// (self-shadowing), R_p rotates it into the vertex's local frame, A_i^-1
// projects it by least squares over the upper hemisphere, B applies the BRDF
// and A_r^-1 projects the exit radiance by least squares into N_r functions.
// The zero-hemisphere variant drops both A^-1 (for comparison, Fig. 7).
#pragma once
#include <Eigen/Core>
#include <vector>

#include "prt/brdf.hpp"
#include "prt/direction_set.hpp"
#include "prt/mesh.hpp"
#include "prt/transfer.hpp"

namespace prt {

class Basis;
class Progress;
class VisibilityBits;

// Orthonormal frame per vertex: rows tangent, bitangent, normal, so that
// frame * world = local. The tangent is world +y projected onto the tangent
// plane (+x near the poles), which fixes the axis of anisotropic BRDFs.
using Frame = Eigen::Matrix3d;
std::vector<Frame> tangent_frames(const Mesh& mesh);

// The constant part of the chain: K = A_r^-1 B A_i^-1 (least squares) or B
// (zero hemisphere), N_r x N_i.
struct GlossyChain {
  ExitBasis exit;
  int light_order = 0;
  bool least_squares = true;
  Eigen::MatrixXd matrix;

  static GlossyChain make(const Brdf& brdf, const ExitBasis& exit, int light_order,
                          bool least_squares, double cutoff);
};

// M_p for every vertex from stored visibility (directions above the tangent
// plane whose rays escape), as rows of N_r x N_i, row-major. The light basis
// must rotate (R_p).
TransferSignal glossy_transfer(const Mesh& mesh, const DirectionSet& directions,
                               const VisibilityBits& visibility, const Basis& light_basis,
                               const GlossyChain& chain, Progress* progress);

// The view direction at each vertex in its local frame (z clamped to the
// upper hemisphere), for a camera at `eye`.
std::vector<Eigen::Vector3d> local_view_directions(const Mesh& mesh,
                                                   const std::vector<Frame>& frames,
                                                   const Eigen::Vector3f& eye);

// Clamps a local direction to the upper hemisphere and normalises it: the
// exit basis is fitted there only.
Eigen::Vector3d upper_hemisphere(Eigen::Vector3d local);

// Exit radiance y(v_p) . e_p per vertex (v x 3) from exit coefficients
// (v x 3 N_r, as exit_coefficients returns).
Eigen::MatrixX3f evaluate_exit(const MatrixXfRow& coefficients, const ExitBasis& exit,
                               const std::vector<Eigen::Vector3d>& local_views);

}  // namespace prt
