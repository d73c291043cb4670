// Distant lighting: an equirectangular HDR map (EXR) or a constant colour,
// with intensity and rotation about the up axis.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <filesystem>
#include <vector>

#include "prt/basis.hpp"

namespace prt {

class Environment {
 public:
  // Loads an equirectangular map: OpenEXR (.exr) or Radiance RGBE (.hdr).
  static Environment load(const std::filesystem::path& file);
  static Environment load_exr(const std::filesystem::path& file);
  static Environment load_hdr(const std::filesystem::path& file);
  static Environment constant(const Eigen::Vector3f& radiance);
  // From raw pixels (row-major RGB, top row = +y pole).
  static Environment from_pixels(int width, int height, std::vector<float> rgb);

  int width() const { return width_; }
  int height() const { return height_; }
  const std::vector<float>& pixels() const { return rgb_; }

  void set_intensity(float intensity) { intensity_ = intensity; }
  // Rotation applied to the map (the environment is turned, not the object).
  void set_rotation(const Eigen::Matrix3d& rotation) { rotation_ = rotation; }
  const Eigen::Matrix3d& rotation() const { return rotation_; }

  // Radiance arriving from world direction `direction` (bilinear, for display).
  Eigen::Vector3f radiance(const Eigen::Vector3d& direction) const;
  // The texel's constant radiance: the piecewise-constant function that the
  // basis projection and the ground truth both integrate.
  Eigen::Vector3f texel_radiance(const Eigen::Vector3d& direction) const;
  // The map coordinates of a world direction (the map's rotation undone), so
  // that a caller needing both a texel and its sampling density finds them
  // with one atan2/acos.
  Eigen::Vector2d uv_of(const Eigen::Vector3d& direction) const;
  Eigen::Vector3f texel_radiance_at(const Eigen::Vector2d& uv) const;

  // Projects the environment into `basis`: size() x 3 (RGB). The map's texels
  // are integrated with their solid angles, a block of rows at a time, each
  // block one matrix product. Rotation is applied through the basis's rotation
  // capability when it has one, otherwise by re-sampling.
  Eigen::MatrixX3d project(const Basis& basis) const;

  // The band-limited light: a map (same resolution; 256 x 128 for a
  // constant) whose texels hold the basis's reconstruction b(d) . light at
  // their centres, with no rotation or intensity of its own (both are in
  // `light`). Ground truth under it isolates the light's truncation from the
  // transfer's projection and compression.
  Environment band_limited(const Basis& basis, const Eigen::MatrixX3d& light) const;

 private:
  Eigen::Vector3f texel(int x, int y) const;
  int width_ = 1, height_ = 1;
  std::vector<float> rgb_{0.f, 0.f, 0.f};
  float intensity_ = 1.0f;
  Eigen::Matrix3d rotation_ = Eigen::Matrix3d::Identity();
};

// Fills `image` with the environment seen through the camera (bilinear): the
// background renderers draw behind the mesh.
struct Camera;
struct Image;
void draw_environment(const Environment& environment, const Camera& camera, Image& image);

// Rotation by `degrees` about the +y (up) axis.
Eigen::Matrix3d rotation_about_up(double degrees);

}  // namespace prt
