// prt-view: loads a scene's bake (baking it when missing) and renders the
// compressed transfer with the OpenGL renderer plug-in, interactively or for a
// scripted number of frames.
//
//   left drag: orbit     right drag or shift + left drag: rotate the light
//   scroll: zoom         Left/Right: rotate the light by 15 degrees
//   ctrl + left drag, J/L (x), U/O (y), I/K (z): move the selected point light
//   E: next encoding (compressed, exact)   H: error heat-map   M: method
//   P: screenshot        Esc or Q: quit
// An ImGui panel shows the plug-ins, encodings, lights and timings, and edits
// the lights.
#include <epoxy/gl.h>
// epoxy before GLFW: it provides the GL declarations.
#include <GLFW/glfw3.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>

#include "panel.hpp"
#include "prt/error.hpp"
#include "prt/image.hpp"
#include "prt/output_file.hpp"
#include "prt/progress.hpp"
#include "prt/registry.hpp"
#include "viewer.hpp"
#include "window.hpp"

namespace {

void apply(prt::view::Viewer& viewer, const prt::view::Input& input, bool& quit, bool& screenshot) {
  viewer.orbit(-0.3 * input.orbit_x, -0.3 * input.orbit_y);
  if (input.light_drag != 0) viewer.rotate_light(0.5 * input.light_drag);
  if (input.zoom != 0) viewer.zoom(input.zoom);
  if (input.point_x != 0 || input.point_y != 0)
    viewer.drag_point_light(input.point_x, input.point_y);
  for (int key : input.keys) {
    switch (key) {
      case GLFW_KEY_J:
        viewer.move_point_light({-1, 0, 0});
        break;
      case GLFW_KEY_L:
        viewer.move_point_light({1, 0, 0});
        break;
      case GLFW_KEY_U:
        viewer.move_point_light({0, 1, 0});
        break;
      case GLFW_KEY_O:
        viewer.move_point_light({0, -1, 0});
        break;
      case GLFW_KEY_I:
        viewer.move_point_light({0, 0, -1});
        break;
      case GLFW_KEY_K:
        viewer.move_point_light({0, 0, 1});
        break;
      case GLFW_KEY_LEFT:
        viewer.rotate_light(-15);
        break;
      case GLFW_KEY_RIGHT:
        viewer.rotate_light(15);
        break;
      case GLFW_KEY_E:
        viewer.next_encoding();
        break;
      case GLFW_KEY_H:
        viewer.toggle_heatmap();
        break;
      case GLFW_KEY_M:
        viewer.toggle_method();
        break;
      case GLFW_KEY_P:
        screenshot = true;
        break;
      case GLFW_KEY_ESCAPE:
      case GLFW_KEY_Q:
        quit = true;
        break;
      default:
        break;
    }
  }
}

// What the command line asks beside the viewer's options: a scripted run.
struct Script {
  int frames = 0;  // 0: interactive
  double light_step = -1, orbit_step = 0;
  std::vector<double> point_step;
  std::string screenshot_file = "prt-view.png";
  bool no_panel = false, no_background = false;
};

void add_options(CLI::App& app, prt::view::Options& options, Script& script) {
  app.add_option("scene", options.scene, "scene description (.toml)")->required();
  app.add_option(
         "--frames", script.frames,
         "render this many frames with a scripted light rotation, then exit (0: interactive)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--light-step", script.light_step,
                 "scripted light rotation per frame, degrees (default 360 / frames)");
  app.add_option("--orbit-step", script.orbit_step, "scripted camera orbit per frame, degrees");
  app.add_option("--point-step", script.point_step,
                 "scripted move of the first point light per frame: x y z, in key presses "
                 "(5% of the mesh's size each)")
      ->expected(3);
  app.add_flag("--no-panel", script.no_panel, "hide the ImGui panel");
  app.add_option("--screenshot", script.screenshot_file,
                 "PNG written after the scripted frames (or P)");
  app.add_option("--method", options.method, "single-pass or per-cluster")
      ->check(CLI::IsMember({"single-pass", "per-cluster"}));
  app.add_flag("--heatmap", options.heatmap, "start in the error heat-map view");
  app.add_flag("--exact", options.exact, "start with the uncompressed transfer");
  app.add_flag("-q,--quiet", options.quiet, "no progress bars");
  app.add_flag("--no-background", script.no_background, "black behind the mesh instead of the map");
}

// Frame after frame until the window closes, Q, or the script's last frame.
void run(prt::view::Viewer& viewer, prt::view::Window& window, Script& script, bool quiet) {
  const int frames = script.frames;
  if (frames > 0 && script.light_step < 0) script.light_step = 360.0 / frames;
  bool quit = false, screenshot = false;
  for (int frame = 0; window.open() && !quit; ++frame) {
    if (frames > 0) {
      if (frame == frames) break;
      if (frame > 0) {
        viewer.rotate_light(script.light_step), viewer.orbit(script.orbit_step, 0);
        if (!script.point_step.empty())
          viewer.move_point_light(
              {script.point_step[0], script.point_step[1], script.point_step[2]});
      }
    }
    const prt::Image image = viewer.render();
    if (script.no_panel)
      window.show(image, viewer.exposure());
    else
      window.show(image, viewer.exposure(), [&] { prt::view::draw_panel(viewer); });
    apply(viewer, window.poll(), quit, screenshot);
    if (frames > 0 && !quiet) std::cout << viewer.status() << "\n";
    if (screenshot || (frames > 0 && frame == frames - 1)) {
      prt::write_png(image, script.screenshot_file, viewer.exposure());
      std::cout << "screenshot -> " << script.screenshot_file << "\n";
      screenshot = false;
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"prt-view: interactive viewer of compressed radiance transfer"};
  prt::view::Options options;
  Script script;
  add_options(app, options, script);
  CLI11_PARSE(app, argc, argv);
  options.background = !script.no_background;
  prt::Progress::set_enabled(!options.quiet);
  try {
    prt::PluginRegistry registry(prt::PluginRegistry::default_directories());
    for (const auto& problem : registry.problems())
      std::cerr << "prt-view: warning: " << problem.message << "\n";
    // The window first: the renderer's own context must go before GLFW does.
    const prt::SceneSpec scene = prt::SceneSpec::load(options.scene, registry);
    std::vector<std::filesystem::path> inputs = scene.input_files();
    inputs.push_back(scene.bake_path());
    prt::check_output({script.screenshot_file, prt::FileKind::png, "screenshot"}, inputs);
    const auto& camera = scene.camera;
    prt::view::Window window(static_cast<int>(prt::keys::camera::width(camera)),
                             static_cast<int>(prt::keys::camera::height(camera)),
                             "prt-view  " + scene.file.filename().string());
    if (!options.quiet) std::cout << "OpenGL: " << window.renderer() << "\n";
    prt::view::Viewer viewer(registry, options);
    run(viewer, window, script, options.quiet);
    return 0;
  } catch (...) {
    std::cerr << "prt-view: " << prt::current_error_line() << "\n";
    return 1;
  }
}
