#include "panel.hpp"

#include <imgui.h>

#include <string>

#include "viewer.hpp"

namespace prt::view {

namespace {

void plugins_section(const Viewer& viewer) {
  const BakeData& data = viewer.bake();
  ImGui::Text("scene  %s", viewer.scene().file.filename().string().c_str());
  ImGui::Text("mesh   %zu vertices, %zu triangles", data.mesh.vertex_count(),
              data.mesh.triangle_count());
  ImGui::TextWrapped("basis  %s", one_line(data.basis).c_str());
  if (data.transfer.glossy()) ImGui::TextWrapped("exit   %s", one_line(data.exit).c_str());
  ImGui::TextWrapped("compressor  %s", one_line(data.compressor).c_str());
  ImGui::Text("material  %s, %d bounces%s", data.material.c_str(), data.bounces,
              data.subsurface ? ", subsurface" : "");
}

void encodings_section(Viewer& viewer) {
  const auto names = viewer.encoding_names();
  for (std::size_t i = 0; i < names.size(); ++i)
    if (ImGui::RadioButton(names[i].c_str(), viewer.encoding() == i)) viewer.set_encoding(i);
  bool heatmap = viewer.heatmap();
  if (ImGui::Checkbox("error heat-map (vs exact)", &heatmap)) viewer.toggle_heatmap();
  ImGui::Text("drawing: %s", viewer.method().c_str());
  ImGui::SameLine();
  if (ImGui::SmallButton("switch")) viewer.toggle_method();
}

void lights_section(Viewer& viewer) {
  float degrees = static_cast<float>(viewer.light_degrees());
  if (ImGui::SliderFloat("environment rotation", &degrees, -360.f, 360.f, "%.0f deg"))
    viewer.set_light_degrees(degrees);
  ImGui::TextWrapped("rotated by %s", viewer.light_rotation_rule().c_str());
  auto& lights = viewer.point_lights();
  if (lights.empty()) {
    ImGui::TextDisabled("no point lights ([[lighting.point]] in the scene)");
    return;
  }
  ImGui::TextWrapped("point lights: %s", viewer.point_light_rule().c_str());
  bool changed = false;
  for (std::size_t i = 0; i < lights.size(); ++i) {
    ImGui::PushID(static_cast<int>(i));
    if (ImGui::RadioButton(("light " + std::to_string(i + 1)).c_str(),
                           viewer.selected_light() == i))
      viewer.selected_light() = i;
    float position[3] = {float(lights[i].position.x()), float(lights[i].position.y()),
                         float(lights[i].position.z())};
    float colour[3] = {float(lights[i].colour.x()), float(lights[i].colour.y()),
                       float(lights[i].colour.z())};
    float intensity = float(lights[i].intensity);
    if (ImGui::DragFloat3("position", position, 0.01f)) {
      lights[i].position = Eigen::Vector3d(position[0], position[1], position[2]);
      changed = true;
    }
    if (ImGui::ColorEdit3("colour", colour)) {
      lights[i].colour = Eigen::Vector3d(colour[0], colour[1], colour[2]);
      changed = true;
    }
    if (ImGui::DragFloat("intensity", &intensity, 0.02f, 0.f, 1e4f)) {
      lights[i].intensity = intensity;
      changed = true;
    }
    ImGui::PopID();
  }
  if (changed) viewer.point_lights_changed();
  ImGui::PushTextWrapPos(0.f);
  ImGui::TextDisabled("keys J/L, U/O, I/K or ctrl + drag move the selected light");
  ImGui::PopTextWrapPos();
}

void timings_section(const Viewer& viewer) {
  const Viewer::Timings t = viewer.timings();
  ImGui::Text("frame    %8.2f ms", t.frame_ms);
  ImGui::Text("relight  %8.2f ms", t.relight_ms);
  ImGui::Text("light    %8.2f ms", t.light_ms);
  ImGui::Text("overdraw %8.3f", t.overdraw);
}

}  // namespace

void draw_panel(Viewer& viewer) {
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(380, 0), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowBgAlpha(0.75f);
  if (!ImGui::Begin("prt-view")) {
    ImGui::End();
    return;
  }
  ImGui::PushItemWidth(-150);  // room for the labels
  if (ImGui::CollapsingHeader("plug-ins", ImGuiTreeNodeFlags_DefaultOpen)) plugins_section(viewer);
  if (ImGui::CollapsingHeader("encodings", ImGuiTreeNodeFlags_DefaultOpen))
    encodings_section(viewer);
  if (ImGui::CollapsingHeader("lights", ImGuiTreeNodeFlags_DefaultOpen)) lights_section(viewer);
  if (ImGui::CollapsingHeader("timings", ImGuiTreeNodeFlags_DefaultOpen)) timings_section(viewer);
  ImGui::PopItemWidth();
  ImGui::End();
}

}  // namespace prt::view
