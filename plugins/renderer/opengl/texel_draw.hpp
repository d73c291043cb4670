// The OpenGL renderer's per-texel path: the mesh with its uvs, and the
// radiance texture (made on the CPU, prt/texel_render.hpp) looked up per
// fragment with GL_LINEAR filtering.
#pragma once
#include <vector>

#include "gl_context.hpp"
#include "prt/renderer.hpp"
#include "prt/texel_render.hpp"
#include "shaders.hpp"

namespace prt {

class TexelDraw {
 public:
  // Draws into the bound framebuffer (cleared here) with `view_projection`.
  void draw(const RenderInput& in, const Eigen::Matrix4f& view_projection) {
    const RadianceTexture texture = texel_texture(in, "opengl");
    upload_mesh(*in.mesh);
    upload_texture(texture);
    glClearColor(0, 0, 0, 0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glUseProgram(program_);
    glBindVertexArray(vao_);
    glUniformMatrix4fv(glGetUniformLocation(program_, "view_projection"), 1, GL_FALSE,
                       view_projection.data());
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, texture_);
    glUniform1i(glGetUniformLocation(program_, "radiance"), 0);
    glDrawElements(GL_TRIANGLES, GLsizei(indices_), GL_UNSIGNED_INT, nullptr);
  }

  // With the renderer's context current.
  void release() {
    if (vao_) glDeleteVertexArrays(1, &vao_);
    if (buffers_[0]) glDeleteBuffers(3, buffers_);
    if (texture_) glDeleteTextures(1, &texture_);
    if (program_) glDeleteProgram(program_);
    vao_ = texture_ = program_ = buffers_[0] = buffers_[1] = buffers_[2] = 0;
    mesh_ = nullptr;
  }

 private:
  // Positions, uvs and triangles: when the mesh changes, not per frame.
  void upload_mesh(const Mesh& mesh) {
    if (vao_ && mesh_ == &mesh && vertices_ == mesh.vertex_count()) return;
    release();
    program_ = build_program("texel", "", kTexelVert, kTexelFrag);
    glGenVertexArrays(1, &vao_);
    glBindVertexArray(vao_);
    glGenBuffers(3, buffers_);
    std::vector<float> positions, uvs;
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
      for (int c = 0; c < 3; ++c) positions.push_back(mesh.positions[v][c]);
      for (int c = 0; c < 2; ++c) uvs.push_back(mesh.uvs[v][c]);
    }
    glBindBuffer(GL_ARRAY_BUFFER, buffers_[0]);
    glBufferData(GL_ARRAY_BUFFER, positions.size() * sizeof(float), positions.data(),
                 GL_STATIC_DRAW);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(0);
    glBindBuffer(GL_ARRAY_BUFFER, buffers_[1]);
    glBufferData(GL_ARRAY_BUFFER, uvs.size() * sizeof(float), uvs.data(), GL_STATIC_DRAW);
    glVertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(1);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, buffers_[2]);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, mesh.triangles.size() * 3 * sizeof(std::uint32_t),
                 mesh.triangles.data(), GL_STATIC_DRAW);
    indices_ = mesh.triangles.size() * 3;
    mesh_ = &mesh;
    vertices_ = mesh.vertex_count();
  }

  // Every frame: the light changes the texels' radiance.
  void upload_texture(const RadianceTexture& texture) {
    if (!texture_) glGenTextures(1, &texture_);
    glBindTexture(GL_TEXTURE_2D, texture_);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB32F, texture.width, texture.height, 0, GL_RGB, GL_FLOAT,
                 texture.texels.data());
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  }

  const Mesh* mesh_ = nullptr;
  std::size_t vertices_ = 0, indices_ = 0;
  GLuint program_ = 0, vao_ = 0, buffers_[3] = {0, 0, 0}, texture_ = 0;
};

}  // namespace prt
