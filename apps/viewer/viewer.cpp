#include "viewer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <iostream>

#include "prt/bake_file.hpp"
#include "prt/output_file.hpp"
#include "prt/progress.hpp"

namespace prt::view {

namespace {

// Blue (no error) -> cyan -> green -> yellow -> red (the largest error).
Eigen::Vector3f heat(float t) {
  t = std::clamp(t, 0.f, 1.f);
  auto ramp = [t](float centre) { return std::clamp(1.5f - std::abs(4.f * t - centre), 0.f, 1.f); };
  return {ramp(3.f), ramp(2.f), ramp(1.f)};
}

}  // namespace

Viewer::Viewer(PluginRegistry& registry, const Options& options)
    : registry_(registry),
      scene_(SceneSpec::load(options.scene, registry)),
      heatmap_(options.heatmap),
      background_(options.background) {
  const auto bake_file = scene_.bake_path();
  if (std::filesystem::exists(bake_file)) {
    data_ = read_bake(bake_file);
    check_bake_records(bake_file.string(), data_, registry_);
  } else {
    std::cerr << "prt-view: " << bake_file.string() << " does not exist; baking it\n";
    check_output({bake_file, FileKind::bake, "bake file", true}, scene_.input_files());
    StageTimes times;
    data_ = prt::bake(scene_, registry_, {options.quiet}, times);
    write_bake(bake_file, data_);
  }
  if (data_.receivers.probes()) {  // docs/receivers.md: shaded from the probes on the CPU
    probes_ = std::make_unique<ProbeView>(scene_, data_, registry_);
    environment_ = scene_.load_environment();
  } else {
    relighting_ = std::make_unique<Relighting>(scene_, data_, registry_);
    light_source_ = std::make_unique<TurningLight>(*relighting_, scene_.load_environment());
  }
  lights_ = scene_.point_lights;
  Eigen::Vector3f low = data_.mesh.positions.front(), high = low;
  for (const auto& p : data_.mesh.positions) low = low.cwiseMin(p), high = high.cwiseMax(p);
  light_step_ = (probes_ ? 0.01 : 0.05) * double((high - low).norm());
  encodings_.push_back({data_.compressor.name, data_.compressed, nullptr});
  encodings_.push_back({"exact", exact_form(data_.transfer), nullptr});
  if (relighting_)
    for (auto& encoding : encodings_)
      encoding.kernel = std::make_unique<RelightKernel>(relighting_->prepare(encoding.transfer));
  current_ = options.exact ? 1 : 0;
  home_ = scene_.make_camera(probes_ ? probes_->display() : data_.mesh);
  exposure_ = static_cast<float>(keys::camera::exposure(scene_.camera));
  // The viewer draws with a renderer that draws on the GPU: the scene's when
  // it does. Its drawing methods, if it has a "method" choice, are what the
  // viewer switches between; the scene's choice (or --method) starts.
  renderer_name_ = gpu_renderer(registry_, scene_.renderer.name);
  if (const ParamSpecRecord* spec =
          registry_.find(PluginKind::renderer, renderer_name_).schema().find("method"))
    methods_ = choices_of(*spec);
  std::string method = options.method;
  if (method.empty() && renderer_name_ == scene_.renderer.name &&
      scene_.renderer.params.has("method"))
    method = scene_.renderer.params.get_string("method");
  if (method.empty() && !methods_.empty()) method = methods_.front();
  make_renderer(method);
}

void Viewer::make_renderer(const std::string& method) {
  Params params(SourceLocation{"prt-view"});
  if (!methods_.empty()) params.set("method", method);
  renderer_ = registry_.create<Renderer>(renderer_name_, params);
  method_ = method;
}

void Viewer::toggle_method() {
  if (methods_.size() < 2) return;
  const auto at = std::find(methods_.begin(), methods_.end(), method_);
  make_renderer(at == methods_.end() || at + 1 == methods_.end() ? methods_.front() : *(at + 1));
}

void Viewer::next_encoding() {
  current_ = (current_ + 1) % encodings_.size();
}

void Viewer::rotate_light(double degrees) {
  light_degrees_ = std::fmod(light_degrees_ + degrees, 360.0);
  light_dirty_ = true;
}

void Viewer::set_light_degrees(double degrees) {
  light_degrees_ = degrees;
  light_dirty_ = true;
}

void Viewer::move_point_light(const Eigen::Vector3d& offset) {
  if (lights_.empty() && probes_) probes_->move((light_step_ * offset).cast<float>());
  if (lights_.empty()) return;
  selected_ = std::min(selected_, lights_.size() - 1);
  lights_[selected_].position += light_step_ * offset;
  point_lights_changed();
}

void Viewer::drag_point_light(double dx, double dy) {
  if (lights_.empty() && !(probes_ && probes_->has_moving())) return;
  const Camera c = camera();
  const Eigen::Vector3d forward = (c.target - c.position).cast<double>().normalized();
  const Eigen::Vector3d right = forward.cross(c.up.cast<double>()).normalized();
  const Eigen::Vector3d up = right.cross(forward);
  move_point_light(0.1 * (dx * right - dy * up));
}

std::vector<std::string> Viewer::encoding_names() const {
  std::vector<std::string> names;
  for (const auto& e : encodings_) names.push_back(e.name);
  return names;
}

std::string Viewer::light_rotation_rule() const {
  return light_source_ ? light_source_->rule() : "the map turned and projected again";
}

void Viewer::orbit(double yaw, double pitch) {
  yaw_ += yaw;
  pitch_ = std::clamp(pitch_ + pitch, -85.0, 85.0);
}

void Viewer::zoom(double steps) {
  distance_scale_ = std::clamp(distance_scale_ * std::pow(0.9, steps), 0.05, 20.0);
}

// The orbit camera (GLM): yaw about the up axis, pitch about the camera's
// side axis, distance scaled by the zoom.
Camera Viewer::camera() const {
  Camera c = home_;
  const glm::vec3 target(c.target.x(), c.target.y(), c.target.z());
  const glm::vec3 up = glm::normalize(glm::vec3(c.up.x(), c.up.y(), c.up.z()));
  const glm::vec3 offset = glm::vec3(c.position.x(), c.position.y(), c.position.z()) - target;
  const glm::vec3 side = glm::normalize(glm::cross(offset, up));
  const glm::mat4 turn = glm::rotate(glm::mat4(1.f), glm::radians(float(yaw_)), up) *
                         glm::rotate(glm::mat4(1.f), glm::radians(float(pitch_)), side);
  const glm::vec3 position =
      target + float(distance_scale_) * glm::vec3(turn * glm::vec4(offset, 0.f));
  c.position = {position.x, position.y, position.z};
  return c;
}

// The light turned by the library's rule (prt/turning_light.hpp).
void Viewer::update_light() {
  if (!light_dirty_) return;
  Stopwatch clock;
  if (probes_) {  // the map turned about +y from the scene's rotation, projected again
    environment_->set_rotation(
        rotation_about_up(keys::lighting::rotation(scene_.lighting) + light_degrees_));
    light_ = probes_->light(*environment_);
  } else {
    light_ = light_source_->at(light_degrees_);
  }
  light_ms_ = 1000 * clock.seconds();
  light_dirty_ = false;
}

// Glossy transfer is folded toward the camera once it rests (the same
// position two frames in a row), so that frames that only turn the light
// cost n_L multiply-adds a vertex and channel (prt/view_transfer.hpp);
// folding costs ~8 of the kernel's frames, so a moving camera keeps the kernel.
Eigen::MatrixX3f Viewer::cpu_radiance(std::size_t index, const Eigen::MatrixX3d& light,
                                      const Camera& cam) {
  Encoding& e = encodings_[index];
  const bool resting = e.last_position && *e.last_position == cam.position;
  e.last_position = cam.position;
  if (resting && !relighting_->sums_here()) {  // not point lights or channel transfers
    if (!e.view_position || *e.view_position != cam.position) {
      e.view = relighting_->view(e.transfer, cam);
      e.view_position = cam.position;
    }
    if (e.view) return relighting_->relight(*e.view, light);
  }
  return relighting_->relight(*e.kernel, light, cam).vertex_radiance;
}

Eigen::MatrixX3f Viewer::heat_colours(const Eigen::MatrixX3d& light, const Camera& cam) {
  const Eigen::MatrixX3f exact = cpu_radiance(1, light, cam);
  const Eigen::MatrixX3f shown = current_ == 1 ? exact : cpu_radiance(current_, light, cam);
  const float scale = std::max(1e-12f, exact.rowwise().norm().maxCoeff());
  Eigen::MatrixX3f colours(shown.rows(), 3);
  for (Eigen::Index p = 0; p < shown.rows(); ++p)
    colours.row(p) = heat(10.f * (shown.row(p) - exact.row(p)).norm() / scale).transpose();
  return colours;  // 10% of the brightest vertex saturates to red
}

// A probe scene: every vertex shaded from the probes on the CPU (the light
// at each probe, then 8 probes a vertex), drawn by the GPU renderer.
Image Viewer::render_probes(const Camera& cam) {
  Eigen::MatrixX3f colours = probes_->radiance(encodings_[current_].transfer, light_);
  relight_ms_ = probes_->incident_ms() + probes_->shade_ms();
  if (heatmap_) {
    const Eigen::MatrixX3f exact = probes_->radiance(encodings_[1].transfer, light_);
    const float scale = std::max(1e-12f, exact.rowwise().norm().maxCoeff());
    for (Eigen::Index p = 0; p < colours.rows(); ++p)
      colours.row(p) = heat(10.f * (colours.row(p) - exact.row(p)).norm() / scale).transpose();
  }
  RenderInput input;
  input.mesh = &probes_->display();
  input.vertex_radiance = &colours;
  input.camera = cam;
  input.background = background_ && !heatmap_ ? &*environment_ : nullptr;
  Image image = renderer_->render(input);
  overdraw_ = 0;
  return image;
}

Image Viewer::render() {
  Stopwatch clock;
  update_light();
  const Camera cam = camera();
  if (probes_) {
    Image image = render_probes(cam);
    frame_ms_ = 1000 * clock.seconds();
    return image;
  }
  // The exit basis toward this camera (glossy); the sums themselves run on the GPU.
  Relit relit;
  if (!relighting_->sums_here()) {
    relit.exit_values = relighting_->exit_values_toward(cam);
  } else {  // point lights or channel transfers: summed here, drawn by the GPU
    Stopwatch relight_clock;
    relit = relighting_->relight(*encodings_[current_].kernel, light_, cam);
    point_ms_ = 1000 * relight_clock.seconds();
  }
  RenderInput input = relighting_->input(encodings_[current_].transfer, relit, light_, cam);
  input.background = background_ ? &light_source_->environment() : nullptr;
  Eigen::MatrixX3f colours;
  if (heatmap_) {
    colours = heat_colours(light_, cam);
    input.vertex_radiance = &colours;
    input.exit_values = nullptr;
    input.albedo = Eigen::Vector3f::Ones();
    input.background = nullptr;
  }
  Image image = renderer_->render(input);
  const auto stats = renderer_->statistics();
  auto stat = [&](const char* key) {
    const auto it = stats.find(key);
    return it == stats.end() ? 0.0 : it->second;
  };
  relight_ms_ = relit.summed ? point_ms_ : 1000 * stat("relight_seconds");
  overdraw_ = stat("overdraw");
  frame_ms_ = 1000 * clock.seconds();
  return image;
}

std::string Viewer::status() const {
  char text[320];
  std::snprintf(text, sizeof text,
                "prt-view  %s | %s%s | %s | frame %.1f ms | relight %.2f ms (light %.2f ms) | "
                "overdraw %.3f | light %.0f deg",
                scene_.file.filename().string().c_str(), encodings_[current_].name.c_str(),
                heatmap_ ? " error heat-map" : "", method_.c_str(), frame_ms_, relight_ms_,
                light_ms_, overdraw_, light_degrees_);
  std::string line = text;
  if (probes_ && probes_->has_moving()) {
    const Eigen::Vector3f& p = probes_->position();
    std::snprintf(text, sizeof text, " | moving object at (%.3f, %.3f, %.3f)", p.x(), p.y(), p.z());
    line += text;
  }
  if (!lights_.empty()) {
    const Eigen::Vector3d& p = lights_[std::min(selected_, lights_.size() - 1)].position;
    std::snprintf(text, sizeof text, " | point light %zu at (%.3f, %.3f, %.3f)",
                  std::min(selected_, lights_.size() - 1) + 1, p.x(), p.y(), p.z());
    line += text;
  }
  return line;
}

}  // namespace prt::view
