#include "gl_context.hpp"

#include <string>
// epoxy before GLFW: it provides the GL declarations.
#include <GLFW/glfw3.h>

#include "prt/error.hpp"

namespace prt {

OffscreenContext::OffscreenContext() {
  if (!glfwInit())
    throw Error(
        "opengl renderer: cannot initialise GLFW (no display?); run under `xvfb-run -a` or use "
        "renderer \"cpu\"");
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  window_ = glfwCreateWindow(16, 16, "prt offscreen", nullptr, nullptr);
  if (!window_)
    throw Error(
        "opengl renderer: cannot create an OpenGL 3.3 core context; run under "
        "`xvfb-run -a` with Mesa, or use renderer \"cpu\"");
  make_current();
}

OffscreenContext::~OffscreenContext() {
  if (window_) glfwDestroyWindow(window_);
}

void OffscreenContext::make_current() {
  glfwMakeContextCurrent(window_);
}

namespace {

GLuint compile(GLenum type, const std::string& source, const char* name) {
  const GLuint shader = glCreateShader(type);
  const char* text = source.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    glDeleteShader(shader);
    throw Error(std::string("opengl renderer: shader ") + name + " does not compile: " + log);
  }
  return shader;
}

}  // namespace

GLuint build_program(const char* name, const std::string& defines, const char* vertex,
                     const char* fragment, const char* captured) {
  const std::string header = "#version 330 core\n" + defines + "#line 1\n";
  const GLuint vs = compile(GL_VERTEX_SHADER, header + vertex, name);
  GLuint fs = 0;
  try {
    fs = compile(GL_FRAGMENT_SHADER, header + fragment, name);
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  if (captured) glTransformFeedbackVaryings(program, 1, &captured, GL_INTERLEAVED_ATTRIBS);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetProgramInfoLog(program, sizeof log, nullptr, log);
    glDeleteProgram(program);
    throw Error(std::string("opengl renderer: program ") + name + " does not link: " + log);
  }
  return program;
}

}  // namespace prt
