// The viewer's window: GLFW with an OpenGL 3.3 core context that shows a
// linear-radiance image (exposure + sRGB in a shader) with a Dear ImGui
// panel over it, and collects the input the panel does not take.
#pragma once
#include <epoxy/gl.h>

#include <functional>
#include <string>
#include <vector>

#include "prt/image.hpp"

struct GLFWwindow;

namespace prt::view {

struct Input {
  double orbit_x = 0, orbit_y = 0;  // left-drag, pixels
  double light_drag = 0;            // right-drag or shift + left-drag, pixels
  double point_x = 0, point_y = 0;  // ctrl + left-drag, pixels: moves the point light
  double zoom = 0;                  // scroll steps
  std::vector<int> keys;            // GLFW key codes pressed since the last poll
};

class Window {
 public:
  Window(int width, int height, const std::string& title);  // throws prt::Error
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  bool open() const;
  void make_current();
  // Draws the image, then `panel` (ImGui calls, if given) over it.
  void show(const Image& image, float exposure, const std::function<void()>& panel = {});
  void set_title(const std::string& title);
  // GL_RENDERER and GL_VERSION of the window's context, e.g. "llvmpipe ... | 4.5 ...".
  std::string renderer() const;
  Input poll();  // processes events; returns the input since the last call

 private:
  static void on_cursor(GLFWwindow* w, double x, double y);
  static void on_scroll(GLFWwindow* w, double dx, double dy);
  static void on_key(GLFWwindow* w, int key, int scancode, int action, int mods);

  GLFWwindow* window_ = nullptr;
  GLuint program_ = 0, texture_ = 0, vao_ = 0;
  double last_x_ = 0, last_y_ = 0;
  bool have_cursor_ = false;
  Input pending_;
};

}  // namespace prt::view
