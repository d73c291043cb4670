// prt-view's state: a bake, its encodings, the light, the orbit camera and the
// OpenGL renderer plug-in; one call renders one frame.
#pragma once
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "probe_view.hpp"
#include "prt/basis.hpp"
#include "prt/environment.hpp"
#include "prt/pipeline.hpp"
#include "prt/renderer.hpp"
#include "prt/scene.hpp"
#include "prt/turning_light.hpp"

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
  void set_light_degrees(double degrees);
  // Moves the selected point light by `offset` (key presses); nothing
  // without lights. In a probe scene without point lights: the moving object.
  void move_point_light(const Eigen::Vector3d& offset);
  // Moves it in the camera's image plane by a mouse drag (pixels).
  void drag_point_light(double dx, double dy);
  // After the panel edited point_lights() in place.
  void point_lights_changed() {
    if (relighting_) relighting_->set_point_lights(lights_);
  }

  const SceneSpec& scene() const { return scene_; }
  const BakeData& bake() const { return data_; }
  float exposure() const { return heatmap_ ? 1.f : exposure_; }
  std::string status() const;  // for the log of scripted runs

  // What the panel shows and edits.
  std::vector<std::string> encoding_names() const;
  std::size_t encoding() const { return current_; }
  void set_encoding(std::size_t index) { current_ = index % encodings_.size(); }
  bool heatmap() const { return heatmap_; }
  const std::string& method() const { return method_; }
  double light_degrees() const { return light_degrees_; }
  std::vector<PointLight>& point_lights() { return lights_; }
  std::size_t& selected_light() { return selected_; }
  std::string point_light_rule() const {
    return relighting_ ? relighting_->point_light_rule() : std::string();
  }
  std::string light_rotation_rule() const;
  struct Timings {
    double frame_ms, relight_ms, light_ms, overdraw;
  };
  Timings timings() const { return {frame_ms_, relight_ms_, light_ms_, overdraw_}; }

 private:
  struct Encoding {
    std::string name;
    CompressedTransfer transfer;
    std::unique_ptr<RelightKernel> kernel;  // laid out once encodings_ is final
    // Glossy: the transfer folded toward a camera that rests (the heat map
    // relights it each frame while only the light turns), where that camera
    // was, and where the previous frame's was.
    std::optional<ViewTransfer> view;
    std::optional<Eigen::Vector3f> view_position, last_position;
  };
  void make_renderer(const std::string& method);
  void update_light();
  Camera camera() const;
  // Vertex radiance of encoding `index` toward `camera` on the CPU.
  Eigen::MatrixX3f cpu_radiance(std::size_t index, const Eigen::MatrixX3d& light,
                                const Camera& camera);
  Eigen::MatrixX3f heat_colours(const Eigen::MatrixX3d& light, const Camera& camera);
  Image render_probes(const Camera& camera);

  PluginRegistry& registry_;
  SceneSpec scene_;
  BakeData data_;
  std::unique_ptr<Relighting> relighting_;  // refers to scene_ and data_; null at probes
  std::unique_ptr<ProbeView> probes_;       // a probe bake: refers to scene_ and data_
  std::optional<Environment> environment_;  // probes: the map, turned by rotate_light
  std::shared_ptr<Renderer> renderer_;
  std::string renderer_name_;         // a renderer that draws on the GPU (gpu_renderer)
  std::vector<std::string> methods_;  // its "method" choices, if it has any
  std::string method_;
  std::unique_ptr<TurningLight> light_source_;  // after relighting_, which it refers to
  Eigen::MatrixX3d light_;
  std::vector<PointLight> lights_;
  std::size_t selected_ = 0;
  double light_step_ = 0.05;  // of the mesh's bounding-box diagonal, per key press
  double light_degrees_ = 0;
  bool light_dirty_ = true, heatmap_ = false, background_ = true;
  std::vector<Encoding> encodings_;
  std::size_t current_ = 0;
  Camera home_;
  double yaw_ = 0, pitch_ = 0, distance_scale_ = 1;
  float exposure_ = 1;
  double frame_ms_ = 0, relight_ms_ = 0, light_ms_ = 0, overdraw_ = 0, point_ms_ = 0;
};

}  // namespace prt::view
