#include "window.hpp"
// epoxy before GLFW: it provides the GL declarations.
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>

#include "display_shaders.hpp"
#include "gl_context.hpp"
#include "prt/error.hpp"

namespace prt::view {

Window::Window(int width, int height, const std::string& title) {
  if (!glfwInit())
    throw Error("prt-view: cannot initialise GLFW (no display?); run under `xvfb-run -a`");
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (!window_) {
    glfwTerminate();
    throw Error("prt-view: cannot open a window with an OpenGL 3.3 core context");
  }
  glfwSetWindowUserPointer(window_, this);
  glfwSetCursorPosCallback(window_, on_cursor);
  glfwSetScrollCallback(window_, on_scroll);
  glfwSetKeyCallback(window_, on_key);
  make_current();
  glfwSwapInterval(0);  // measure frames, not the display's refresh
  program_ = build_program("display", "", kDisplayVert, kDisplayFrag);
  glGenVertexArrays(1, &vao_);
  glGenTextures(1, &texture_);
  glBindTexture(GL_TEXTURE_2D, texture_);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  // ImGui after our callbacks: its GLFW back end calls them on.
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini in the user's folder
  ImGui::StyleColorsDark();
  if (!ImGui_ImplGlfw_InitForOpenGL(window_, true) || !ImGui_ImplOpenGL3_Init("#version 330"))
    throw Error("prt-view: cannot set up the ImGui panel on this OpenGL context");
}

Window::~Window() {
  if (window_) {
    make_current();
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
    glDeleteTextures(1, &texture_);
    glDeleteVertexArrays(1, &vao_);
    glDeleteProgram(program_);
    glfwDestroyWindow(window_);
  }
  glfwTerminate();
}

bool Window::open() const {
  return !glfwWindowShouldClose(window_);
}

void Window::make_current() {
  glfwMakeContextCurrent(window_);
}

void Window::show(const Image& image, float exposure, const std::function<void()>& panel) {
  make_current();
  int width = 0, height = 0;
  glfwGetFramebufferSize(window_, &width, &height);
  glViewport(0, 0, width, height);
  glBindTexture(GL_TEXTURE_2D, texture_);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB32F, image.width, image.height, 0, GL_RGB, GL_FLOAT,
               image.rgb.data());
  glUseProgram(program_);
  glUniform1i(glGetUniformLocation(program_, "image"), 0);
  glUniform1f(glGetUniformLocation(program_, "exposure"), exposure);
  glBindVertexArray(vao_);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  if (panel) {
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    panel();
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  }
  glfwSwapBuffers(window_);
}

std::string Window::renderer() const {
  const auto* name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  return std::string(name ? name : "?") + " | " + (version ? version : "?");
}

void Window::set_title(const std::string& title) {
  glfwSetWindowTitle(window_, title.c_str());
}

Input Window::poll() {
  glfwPollEvents();
  Input out = std::move(pending_);
  pending_ = Input();
  return out;
}

void Window::on_cursor(GLFWwindow* w, double x, double y) {
  auto* self = static_cast<Window*>(glfwGetWindowUserPointer(w));
  const double dx = x - self->last_x_, dy = y - self->last_y_;
  self->last_x_ = x, self->last_y_ = y;
  if (!self->have_cursor_) {
    self->have_cursor_ = true;
    return;
  }
  if (ImGui::GetIO().WantCaptureMouse) return;  // dragging in the panel
  const bool left = glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
  const bool right = glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS;
  const bool shift = glfwGetKey(w, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ||
                     glfwGetKey(w, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS;
  const bool control = glfwGetKey(w, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS ||
                       glfwGetKey(w, GLFW_KEY_RIGHT_CONTROL) == GLFW_PRESS;
  if (left && control) {
    self->pending_.point_x += dx;
    self->pending_.point_y += dy;
  } else if (right || (left && shift)) {
    self->pending_.light_drag += dx;
  } else if (left) {
    self->pending_.orbit_x += dx;
    self->pending_.orbit_y += dy;
  }
}

void Window::on_scroll(GLFWwindow* w, double, double dy) {
  if (ImGui::GetIO().WantCaptureMouse) return;
  static_cast<Window*>(glfwGetWindowUserPointer(w))->pending_.zoom += dy;
}

void Window::on_key(GLFWwindow* w, int key, int, int action, int) {
  if (ImGui::GetIO().WantCaptureKeyboard) return;  // typing into the panel
  if (action == GLFW_PRESS || action == GLFW_REPEAT)
    static_cast<Window*>(glfwGetWindowUserPointer(w))->pending_.keys.push_back(key);
}

}  // namespace prt::view
