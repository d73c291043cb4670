// The scene description (TOML): which mesh, material, lighting and plug-ins a
// run uses. Every key is validated before any work starts.
#pragma once
#include <filesystem>
#include <string>

#include "prt/camera.hpp"
#include "prt/direction_set.hpp"
#include "prt/params.hpp"

namespace prt {

class PluginRegistry;
struct Mesh;
class Environment;

struct PluginChoice {
  std::string name;
  SourceLocation where;
  Params params;
};

struct SceneSpec {
  std::filesystem::path file;  // the scene file; relative paths resolve against its folder
  std::string text;            // the file's text, stored in bake files

  Params mesh, material, transport, lighting, camera, output, ground_truth;
  PluginChoice basis, compressor, renderer;

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

  Mesh load_mesh() const;
  DirectionSet directions() const;  // [transport] directions, rays, seed
  Environment load_environment() const;
  Camera make_camera(const Mesh& mesh) const;
  Eigen::Vector3f albedo() const;
};

}  // namespace prt
