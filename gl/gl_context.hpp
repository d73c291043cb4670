// An OpenGL 3.3 core context of its own (a hidden GLFW window), for rendering
// off screen; under Xvfb + Mesa when there is no display.
#pragma once
#include <epoxy/gl.h>

#include <string>

struct GLFWwindow;

namespace prt {

class OffscreenContext {
 public:
  OffscreenContext();  // throws prt::Error with what to do when no context can be had
  ~OffscreenContext();
  OffscreenContext(const OffscreenContext&) = delete;
  OffscreenContext& operator=(const OffscreenContext&) = delete;
  void make_current();

 private:
  GLFWwindow* window_ = nullptr;
};

// Compiles and links a program from the shader sources with `defines`
// prepended (after #version); throws prt::Error with the driver's log.
// `captured`, when given, names a vertex-shader output that transform
// feedback writes to a buffer.
GLuint build_program(const char* name, const std::string& defines, const char* vertex,
                     const char* fragment, const char* captured = nullptr);

}  // namespace prt
