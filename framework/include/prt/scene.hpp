// The scene description (TOML): which mesh, material, lighting and plug-ins a
// run uses. Every key is validated before any work starts.
#pragma once
#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "prt/brdf.hpp"
#include "prt/camera.hpp"
#include "prt/direction_set.hpp"
#include "prt/params.hpp"
#include "prt/point_lights.hpp"
#include "prt/scene_keys.hpp"
#include "prt/subsurface.hpp"
#include "prt/transfer.hpp"

namespace prt {

class PluginRegistry;
struct Mesh;
class Environment;
class Basis;

// One colour channel's material: what that channel's transfer depends on.
struct ChannelMaterial {
  Brdf brdf;                      // the channel's kd and ks
  SubsurfaceMaterial subsurface;  // the channel's sigma_a and sigma_s
  double bounce_albedo = 1;       // reflectance of inter-reflected light
};

// The distinct channel materials of a scene (Sloan 2003 keeps one transfer
// and tints it; channels whose transfers differ get their own): channels
// that share a material share a transfer.
struct MaterialChannels {
  std::vector<ChannelMaterial> groups;
  std::array<int, 3> group_of_channel{0, 0, 0};
};

struct PluginChoice {
  std::string name;
  SourceLocation where;
  Params params;
};

struct SceneSpec {
  std::filesystem::path file;  // the scene file; relative paths resolve against its folder
  std::string text;            // the file's text, stored in bake files

  Params mesh, material, transport, lighting, camera, output, ground_truth;
  Params receivers;                // [receivers]: vertices (default) or probes
  Params moving;                   // [moving]: probe scenes' object shaded from the probes
  bool moving_given = false;       // the scene has a [moving] section
  std::vector<Params> mesh_parts;  // [[mesh.add]]: meshes placed and joined to [mesh]
  PluginChoice basis, compressor, renderer;
  PluginChoice exit;  // [exit]: the hemisphere basis of glossy exit radiance (glossy only)
  std::vector<PointLight> point_lights;  // [[lighting.point]]

  // Parses and validates the whole scene, plug-in parameters included.
  // Throws prt::Error with file:line:column on the first problem.
  static SceneSpec load(const std::filesystem::path& file, const PluginRegistry& registry);
  static SceneSpec parse(const std::string& text, const std::filesystem::path& file,
                         const PluginRegistry& registry);

  std::filesystem::path resolve(const std::string& relative) const;
  // Output paths: from [output] (relative to the scene) or <stem>.h5 / <stem>.png
  // in the current directory.
  std::filesystem::path bake_path() const;
  std::filesystem::path image_path() const;
  // Files a run reads (the scene, its mesh and environment map): no output
  // may be written over them.
  std::vector<std::filesystem::path> input_files() const;

  // The scene's mesh with every [[mesh.add]] joined to it.
  Mesh load_mesh() const;
  bool probes() const;      // [receivers] kind = "probes"
  bool texels() const;      // [receivers] kind = "texels"
  bool has_moving() const;  // a [moving] section
  // The [moving] object placed at `position` (default: the scene's).
  Mesh load_moving() const;
  Mesh load_moving(const Eigen::Vector3f& position) const;
  DirectionSet directions() const;  // [transport] directions, rays, seed
  Environment load_environment() const;
  // The environment projected into the basis, with [lighting] window applied.
  Eigen::MatrixX3d project_light(const Environment& environment, const Basis& basis) const;
  Camera make_camera(const Mesh& mesh) const;
  // RGB factor applied to the transfer's radiance: albedo (x diffuse for lambert).
  Eigen::Vector3f albedo() const;
  // The BRDF of colour channel `channel` (0 red, 1 green, 2 blue).
  Brdf brdf(int channel = 0) const;
  bool glossy() const;  // a glossy BRDF: bake matrices, not vectors
  // Throws unless [lighting] window is "none" or the basis has frequency bands.
  void check_window(const Basis& light_basis) const;
  // The SH order M of the BRDF's incident side for this light basis.
  int incident_order(const Basis& light_basis) const;
  // The reflectance of inter-reflected light in a channel: its diffuse (for
  // lambert) x the mean albedo (the RGB albedo tints the final radiance).
  double bounce_albedo(int channel = 0) const;
  // A channel's subsurface coefficients ([material] preset or sigma_a, sigma_s).
  SubsurfaceMaterial subsurface(int channel = 0) const;
  // Which channels need transfers of their own: a coloured diffuse or
  // specular where the transfer holds the BRDF (glossy, or bounces), or
  // coloured subsurface coefficients. One group when the channels agree.
  MaterialChannels channels() const;
  // Everything about the material a bake depends on (recorded in bake files).
  std::string material_description() const;
};

}  // namespace prt
