// View-independent multiple scattering (Sloan 2003 §3.1 after Jensen & Buhler
// 2002): the dipole diffusion profile R_d (Jensen et al. 2001) summed over
// the surface with a point hierarchy, parameterised by the light basis:
//   s_p = (1 - F_dr)^2 sum_q R_d(|x_p - x_q|) A_q t_q
// where t_q = int V cos y / pi is the shadowed diffuse transfer (irradiance
// / pi per light coefficient) and A_q the vertex's area. Distant groups of
// points whose radius is below `error` x their distance enter as one point
// (area-weighted centroid and transfer sum), as in Jensen & Buhler's octree.
// Coefficients are monochrome: one sigma_a, sigma_s', eta; the material's RGB
// albedo tints the result like the rest of the transfer.
#pragma once
#include <Eigen/Core>
#include <memory>
#include <string>

#include "prt/mesh.hpp"
#include "prt/transfer.hpp"

namespace prt {

struct SubsurfaceMaterial {
  double sigma_a = 0.0041;   // absorption, 1/mm (marble, Jensen et al. 2001)
  double sigma_s = 2.62;     // reduced scattering sigma_s', 1/mm
  double eta = 1.5;          // relative index of refraction
  double mm_per_unit = 100;  // millimetres per mesh unit
  double error = 0.3;        // hierarchy: radius / distance below which a group is one point
};

// Jensen et al. 2001 (Fig. 5): measured reduced scattering sigma_s' and
// absorption sigma_a, 1/mm, per RGB channel, with eta = 1.3.
struct SubsurfacePreset {
  const char* name;
  double sigma_s[3], sigma_a[3];
};
// The named preset ("marble", "skin1", "ketchup", ...), or nullptr.
const SubsurfacePreset* subsurface_preset(const std::string& name);

// Diffuse Fresnel reflectance F_dr(eta) (polynomial fit of Jensen et al. 2001).
double diffuse_fresnel_reflectance(double eta);
// The dipole profile R_d(r), r in mm, in 1/mm^2.
double dipole_profile(const SubsurfaceMaterial& m, double r_mm);
// int R_d dA over a plane: the total diffuse reflectance of a half space.
double dipole_total_reflectance(const SubsurfaceMaterial& m);

// s_p per vertex for the diffuse transfer `irradiance_transfer` (v x n).
MatrixXfRow subsurface_transfer(const Mesh& mesh, const MatrixXfRow& irradiance_transfer,
                                const SubsurfaceMaterial& material);

// The same in parts: the hierarchy over every vertex is built once, then
// s_p is gathered for any range of vertices (a slab of a checkpointed bake).
// Keeps a reference to `irradiance_transfer`.
class SubsurfaceScattering {
 public:
  SubsurfaceScattering(const Mesh& mesh, const MatrixXfRow& irradiance_transfer,
                       const SubsurfaceMaterial& material);
  ~SubsurfaceScattering();
  SubsurfaceScattering(const SubsurfaceScattering&) = delete;
  SubsurfaceScattering& operator=(const SubsurfaceScattering&) = delete;
  // s_p of vertices [first, last), a row each.
  MatrixXfRow rows(std::size_t first, std::size_t last) const;

 private:
  struct Hierarchy;
  std::unique_ptr<const Hierarchy> hierarchy_;
};

// The ground truth's multiple scattering: the same dipole summed directly
// over every pair of vertices (no hierarchy, no basis), from the irradiance
// each vertex receives given as E / pi (v x 3: the exit radiance of a white
// Lambertian surface, e.g. Monte Carlo with visibility). Returns v x 3.
Eigen::MatrixX3f subsurface_direct(const Mesh& mesh, const Eigen::MatrixX3f& irradiance,
                                   const SubsurfaceMaterial& material);
// The same for any number of irradiance columns (v x k; e.g. the Monte Carlo
// batches of several estimates at once: the pair kernel, the cost, is
// evaluated once for all columns).
Eigen::MatrixXf subsurface_direct_columns(const Mesh& mesh, const Eigen::MatrixXf& irradiance,
                                          const SubsurfaceMaterial& material);

// A third of the area of each triangle around each vertex (mesh units^2).
std::vector<double> vertex_areas(const Mesh& mesh);

}  // namespace prt
