// prt-view's state: a bake, its encodings, the light, the orbit camera and the
// OpenGL renderer plug-in; one call renders one frame.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "prt/basis.hpp"
#include "prt/environment.hpp"
#include "prt/pipeline.hpp"
#include "prt/renderer.hpp"
#include "prt/scene.hpp"

namespace prt::view {

struct Options {
  std::string scene;
  std::string method;  // renderer method; empty: the scene's, else single-pass
  bool heatmap = false;
  bool exact = false;  // start with the uncompressed transfer
  bool quiet = false;
  bool background = true;  // the environment behind the mesh
};

class Viewer {
 public:
  Viewer(PluginRegistry& registry, const Options& options);
  // relighting_ refers to scene_ and data_: a viewer stays where it was made.
  Viewer(const Viewer&) = delete;
  Viewer& operator=(const Viewer&) = delete;

  Image render();  // one frame at the current light and camera
  void rotate_light(double degrees);
  void orbit(double yaw_degrees, double pitch_degrees);
  void zoom(double steps);
  void next_encoding();
  void toggle_heatmap() { heatmap_ = !heatmap_; }
  void toggle_method();

  const SceneSpec& scene() const { return scene_; }
  float exposure() const { return heatmap_ ? 1.f : exposure_; }
  std::string status() const;  // for the title bar and the log

 private:
  struct Encoding {
    std::string name;
    CompressedTransfer transfer;
    std::unique_ptr<RelightKernel> kernel;  // laid out once encodings_ is final
  };
  void make_renderer(const std::string& method);
  void update_light();
  Camera camera() const;
  Eigen::MatrixX3f heat_colours(const Eigen::MatrixX3d& light, const Camera& camera) const;

  PluginRegistry& registry_;
  SceneSpec scene_;
  BakeData data_;
  std::unique_ptr<Relighting> relighting_;  // refers to scene_ and data_
  std::shared_ptr<Renderer> renderer_;
  std::string method_;
  Environment environment_;
  Eigen::Matrix3d scene_rotation_;
  Eigen::MatrixX3d base_light_, light_;
  double light_degrees_ = 0;
  bool light_dirty_ = true, heatmap_ = false, background_ = true;
  std::vector<Encoding> encodings_;
  std::size_t current_ = 0;
  Camera home_;
  double yaw_ = 0, pitch_ = 0, distance_scale_ = 1;
  float exposure_ = 1;
  double frame_ms_ = 0, relight_ms_ = 0, light_ms_ = 0, overdraw_ = 0;
};

}  // namespace prt::view
