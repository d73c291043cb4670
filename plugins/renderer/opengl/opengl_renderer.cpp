// The OpenGL renderer (Sloan 2003 §6): per-cluster constants M_ki l on the
// CPU, per-vertex weighted sums in the vertex shader, glossy y(v_p) . e_p per
// vertex with the exit basis's values toward the camera (any exit basis). Two methods: one indexed
// pass with the cluster index as a vertex attribute ("single-pass"), or the paper's per-cluster
// draws with additive blending and a partition of unity
// ("per-cluster"; superclusters when the compressor made them), whose
// overdraw is counted.
#include <array>
#include <chrono>

#include "gl_context.hpp"
#include "prt/environment.hpp"
#include "prt/plugin.hpp"
#include "prt/relight.hpp"
#include "prt/renderer.hpp"
#include "shaders.hpp"
#include "texel_draw.hpp"

namespace prt {

namespace {

// A texture buffer: the data lives in a buffer object, read with texelFetch.
struct TextureBuffer {
  GLuint buffer = 0, texture = 0;
  void upload(GLenum format, const void* data, std::size_t bytes) {
    if (!buffer) glGenBuffers(1, &buffer), glGenTextures(1, &texture);
    glBindBuffer(GL_TEXTURE_BUFFER, buffer);
    // An empty buffer object cannot back a texture: keep at least one texel.
    static const float zero[4] = {0, 0, 0, 0};
    glBufferData(GL_TEXTURE_BUFFER, bytes ? bytes : sizeof zero, bytes ? data : zero,
                 GL_DYNAMIC_DRAW);
    glBindTexture(GL_TEXTURE_BUFFER, texture);
    glTexBuffer(GL_TEXTURE_BUFFER, format, buffer);
  }
  void bind(GLuint program, const char* name, int unit) const {
    glActiveTexture(GL_TEXTURE0 + unit);
    glBindTexture(GL_TEXTURE_BUFFER, texture);
    glUniform1i(glGetUniformLocation(program, name), unit);
  }
  void release() {
    if (buffer) glDeleteBuffers(1, &buffer), glDeleteTextures(1, &texture);
    buffer = texture = 0;
  }
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

class OpenGLRenderer final : public Renderer {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description =
      "OpenGL 3.3: per-cluster constants on the CPU, weighted sums and glossy evaluation on the "
      "GPU";
  static constexpr auto kMethod =
      param::choice("method", "single-pass", "single-pass|per-cluster",
                    "one indexed draw, or the paper's per-cluster draws with blending");
  static constexpr auto kBackground =
      param::boolean("background", "true", "draw the environment behind the mesh");
  static constexpr auto parameters() { return param::records(kMethod, kBackground); }

  explicit OpenGLRenderer(const Params& params)
      : per_cluster_(kMethod(params) == "per-cluster"), background_(kBackground(params)) {}

  ~OpenGLRenderer() override {
    if (!context_) return;
    context_->make_current();
    release();
  }

  Image render(const RenderInput& in) override {
    if (!in.mesh) throw Error("opengl renderer: no mesh");
    if (!context_) context_ = std::make_unique<OffscreenContext>();
    context_->make_current();
    const Camera& camera = in.camera;
    prepare_framebuffer(camera.width, camera.height);
    if (in.texels) return draw_texels(in);
    upload_scene(in);
    const auto start = std::chrono::steady_clock::now();
    upload_constants(in);
    stats_["relight_seconds"] = seconds_since(start);
    const auto draw_start = std::chrono::steady_clock::now();
    draw(in);
    glFinish();
    stats_["draw_seconds"] = seconds_since(draw_start);
    return read_image(in);
  }

  std::map<std::string, double> statistics() const override { return stats_; }
  bool draws_on_gpu() const override { return true; }

 private:
  // Per-texel transfer: the radiance texture looked up per fragment.
  Image draw_texels(const RenderInput& in) {
    const auto start = std::chrono::steady_clock::now();
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
    glViewport(0, 0, width_, height_);
    texel_draw_.draw(in, view_projection(in.camera, *in.mesh));
    glFinish();
    stats_["draw_seconds"] = seconds_since(start);
    return read_image(in);
  }

  // ---- resources ---------------------------------------------------------
  void prepare_framebuffer(int width, int height) {
    if (framebuffer_ && width == width_ && height == height_) return;
    if (framebuffer_) {
      glDeleteFramebuffers(1, &framebuffer_);
      glDeleteRenderbuffers(2, renderbuffers_);
    }
    width_ = width, height_ = height;
    glGenFramebuffers(1, &framebuffer_);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
    glGenRenderbuffers(2, renderbuffers_);
    glBindRenderbuffer(GL_RENDERBUFFER, renderbuffers_[0]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA32F, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                              renderbuffers_[0]);
    glBindRenderbuffer(GL_RENDERBUFFER, renderbuffers_[1]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                              renderbuffers_[1]);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw Error("opengl renderer: cannot make a " + std::to_string(width) + "x" +
                  std::to_string(height) + " float framebuffer");
  }

  // Geometry, weights and cluster indices: uploaded when the mesh or the
  // transfer changes (the viewer switches encodings), not per frame.
  void upload_scene(const RenderInput& in) {
    const Mesh& mesh = *in.mesh;
    const bool glossy = in.exit_values != nullptr && !in.vertex_radiance;
    if (!in.transfer && !in.vertex_radiance)
      throw Error("opengl renderer: neither transfer nor vertex radiance given");
    const CompressedTransfer* t = in.vertex_radiance ? nullptr : in.transfer;
    const int rows = glossy ? static_cast<int>(in.exit_values->cols()) : 1;
    if (glossy && in.exit_values->rows() != static_cast<Eigen::Index>(mesh.vertex_count()))
      throw Error("opengl renderer: exit values do not match the mesh's vertices");
    // Identity and shape of the data: a caller may reuse an address for new data.
    const Key key{&mesh,
                  mesh.vertex_count(),
                  t,
                  t ? t->dimension : 0,
                  t ? t->components : 0,
                  t ? t->clusters() : 0,
                  t ? t->weights.data() : nullptr,
                  t ? t->supercluster_of_cluster.size() : 0,
                  t && t->sparse(),
                  rows,
                  per_cluster_};
    if (program_ && key == key_) return;
    release();
    key_ = key;
    glGenVertexArrays(1, &vao_);
    glBindVertexArray(vao_);
    const std::size_t v = mesh.vertex_count();
    std::vector<float> positions(3 * v);
    for (std::size_t p = 0; p < v; ++p)
      for (int c = 0; c < 3; ++c) positions[3 * p + c] = mesh.positions[p][c];
    glGenBuffers(1, &vertex_buffer_);
    glBindBuffer(GL_ARRAY_BUFFER, vertex_buffer_);
    glBufferData(GL_ARRAY_BUFFER, positions.size() * sizeof(float), positions.data(),
                 GL_STATIC_DRAW);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(0);
    build_index_buffer(mesh, t);
    vertices_ = v;

    std::string defines =
        "#define ROWS " + std::to_string(rows) + "\n#define GLOSSY " + (glossy ? "1" : "0") + "\n";
    // One draw of all clusters (not the paper's per-cluster passes): shade
    // each vertex once into a buffer, then draw it as plain vertex colours.
    capture_ = t && groups_.size() == 1;
    if (!t) {
      defines += "#define COMPONENTS -1\n#define SPARSE 0\n#define ATTRIBUTES 0\n";
    } else {
      defines += "#define COMPONENTS " + std::to_string(t->components) + "\n#define SPARSE " +
                 (t->sparse() ? "1" : "0") + "\n";
      if (t->sparse() && glossy)
        throw Error("opengl renderer: sparse glossy transfer is not supported");
      // Vertex attributes are read for every drawn vertex: sizes must agree.
      if (t->vertices() != static_cast<Eigen::Index>(mesh.vertex_count()))
        throw Error("opengl renderer: the transfer has " + std::to_string(t->vertices()) +
                    " vertices, the mesh " + std::to_string(mesh.vertex_count()));
      cluster_of_vertex_.upload(GL_R32I, t->cluster_of_vertex.data(),
                                t->cluster_of_vertex.size() * sizeof(std::int32_t));
      weights_.upload(GL_R32F, t->weights.data(), t->weights.size() * sizeof(float));
      // Where n' fits the vertex attributes, weights and cluster index come
      // in with the vertex (no texture fetches per weight).
      const int vec4s = (t->components + 3) / 4;
      const bool attributes = !t->sparse() && vec4s <= kMaxWeightVec4s;
      defines += std::string("#define ATTRIBUTES ") + (attributes ? "1" : "0") +
                 "\n#define WEIGHT_VEC4S " + std::to_string(std::max(vec4s, 1)) + "\n";
      if (attributes) upload_weight_attributes(*t, vec4s);
      weight_index_.upload(GL_R32I, t->weight_index.data(),
                           t->weight_index.size() * sizeof(std::int32_t));
    }
    defines += std::string("#define CAPTURE ") + (capture_ ? "1" : "0") + "\n";
    program_ = build_program("transfer", defines, kTransferVert, kTransferFrag,
                             capture_ ? "captured" : nullptr);
    if (capture_) {
      captured_.upload(GL_RGBA32F, nullptr, v * 4 * sizeof(float));
      plain_program_ = build_program("captured colours",
                                     "#define ROWS 1\n#define GLOSSY 0\n#define COMPONENTS -1\n"
                                     "#define SPARSE 0\n#define ATTRIBUTES 0\n#define CAPTURE 0\n",
                                     kTransferVert, kTransferFrag);
    }
  }

  // Cluster index (location 1) and weights padded to whole vec4s (locations
  // 2, 3, ...) as vertex attributes.
  void upload_weight_attributes(const CompressedTransfer& t, int vec4s) {
    const std::size_t v = t.cluster_of_vertex.size();
    glGenBuffers(1, &cluster_attribute_buffer_);
    glBindBuffer(GL_ARRAY_BUFFER, cluster_attribute_buffer_);
    glBufferData(GL_ARRAY_BUFFER, v * sizeof(std::int32_t), t.cluster_of_vertex.data(),
                 GL_STATIC_DRAW);
    glVertexAttribIPointer(1, 1, GL_INT, 0, nullptr);
    glEnableVertexAttribArray(1);
    if (t.components == 0) return;
    std::vector<float> padded(v * 4 * vec4s, 0.f);
    for (std::size_t p = 0; p < v; ++p)
      std::copy_n(t.weights.row(Eigen::Index(p)).data(), t.components, &padded[p * 4 * vec4s]);
    glGenBuffers(1, &weight_attribute_buffer_);
    glBindBuffer(GL_ARRAY_BUFFER, weight_attribute_buffer_);
    glBufferData(GL_ARRAY_BUFFER, padded.size() * sizeof(float), padded.data(), GL_STATIC_DRAW);
    const GLsizei stride = 4 * vec4s * sizeof(float);
    for (int i = 0; i < vec4s; ++i) {
      glVertexAttribPointer(2 + i, 4, GL_FLOAT, GL_FALSE, stride,
                            reinterpret_cast<const void*>(std::size_t(16 * i)));
      glEnableVertexAttribArray(2 + i);
    }
  }

  // One index buffer; per-cluster drawing orders it by group (cluster, or
  // supercluster when present), each group's range holding every triangle
  // with a vertex in the group, so straddling triangles are drawn once per
  // group they touch.
  void build_index_buffer(const Mesh& mesh, const CompressedTransfer* t) {
    std::vector<std::uint32_t> indices;
    groups_.clear();
    if (per_cluster_ && t && !t->sparse()) {
      auto group_of_vertex = [&](std::uint32_t p) {
        const int k = t->cluster_of_vertex[p];
        return t->supercluster_of_cluster.empty() ? k : t->supercluster_of_cluster[k];
      };
      int groups = 0;
      for (std::size_t p = 0; p < mesh.vertex_count(); ++p)
        groups = std::max(groups, group_of_vertex(std::uint32_t(p)) + 1);
      std::vector<std::vector<std::uint32_t>> per_group(groups);
      for (const auto& tri : mesh.triangles) {
        std::array<int, 3> g{group_of_vertex(tri[0]), group_of_vertex(tri[1]),
                             group_of_vertex(tri[2])};
        for (int i = 0; i < 3; ++i)
          if ((i == 0 || g[i] != g[0]) && (i < 2 || g[2] != g[1]))
            per_group[g[i]].insert(per_group[g[i]].end(), tri.begin(), tri.end());
      }
      for (int g = 0; g < groups; ++g) {
        groups_.push_back({g, indices.size(), per_group[g].size()});
        indices.insert(indices.end(), per_group[g].begin(), per_group[g].end());
      }
    } else {
      for (const auto& tri : mesh.triangles) indices.insert(indices.end(), tri.begin(), tri.end());
      groups_.push_back({-1, 0, indices.size()});
    }
    glGenBuffers(1, &index_buffer_);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, index_buffer_);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, indices.size() * sizeof(std::uint32_t), indices.data(),
                 GL_STATIC_DRAW);
    // Group membership by cluster, for the shader's partition of unity.
    std::vector<std::int32_t> group_of_cluster;
    if (t && !t->supercluster_of_cluster.empty()) {
      group_of_cluster = t->supercluster_of_cluster;
    } else if (t) {
      group_of_cluster.resize(static_cast<std::size_t>(t->clusters()));
      for (std::size_t k = 0; k < group_of_cluster.size(); ++k) group_of_cluster[k] = int(k);
    }
    group_of_cluster_.upload(GL_R32I, group_of_cluster.data(),
                             group_of_cluster.size() * sizeof(std::int32_t));
    const double drawn = static_cast<double>(indices.size() / 3);
    stats_["triangles_drawn"] = drawn;
    stats_["overdraw"] = mesh.triangles.empty() ? 0.0 : drawn / double(mesh.triangles.size());
  }

  // Per-cluster constants (the CPU side of relighting), every frame.
  void upload_constants(const RenderInput& in) {
    std::vector<float> texels;
    if (in.vertex_radiance) {
      const Eigen::MatrixX3f& r = *in.vertex_radiance;
      texels.resize(4 * r.rows());
      for (Eigen::Index p = 0; p < r.rows(); ++p)
        for (int c = 0; c < 3; ++c) texels[4 * p + c] = std::max(0.f, r(p, c) * in.albedo[c]);
      vertex_colour_.upload(GL_RGBA32F, texels.data(), texels.size() * sizeof(float));
      return;
    }
    const CompressedTransfer& t = *in.transfer;
    const int rows = in.exit_values ? static_cast<int>(in.exit_values->cols()) : 1;
    if (in.exit_values)  // the exit basis toward the camera: changes with the view
      exit_values_.upload(GL_R32F, in.exit_values->data(), in.exit_values->size() * sizeof(float));
    if (t.sparse()) {
      // [mean . l, l_0, l_1, ...]
      const Eigen::RowVector3f base = t.means.row(0) * in.light.cast<float>();
      texels.assign(4 * (in.light.rows() + 1), 0.f);
      for (int c = 0; c < 3; ++c) texels[c] = base[c];
      for (Eigen::Index j = 0; j < in.light.rows(); ++j)
        for (int c = 0; c < 3; ++c) texels[4 * (j + 1) + c] = float(in.light(j, c));
    } else {
      // Per cluster (n' + 1) x rows RGB texels, padded with zeros past n'_k.
      const std::vector<MatrixXfRow> constants = cluster_constants(t, in.light, rows);
      const std::size_t per_cluster = std::size_t(t.components + 1) * rows;
      texels.assign(4 * per_cluster * constants.size(), 0.f);
      for (std::size_t k = 0; k < constants.size(); ++k)
        for (Eigen::Index i = 0; i < constants[k].rows(); ++i)
          for (int r = 0; r < rows; ++r)
            for (int c = 0; c < 3; ++c)
              texels[4 * (k * per_cluster + i * rows + r) + c] = constants[k](i, 3 * r + c);
    }
    constants_.upload(GL_RGBA32F, texels.data(), texels.size() * sizeof(float));
  }

  void draw(const RenderInput& in) {
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
    glViewport(0, 0, width_, height_);
    glClearColor(0, 0, 0, 0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glUseProgram(program_);
    glBindVertexArray(vao_);
    const Eigen::Matrix4f vp = view_projection(in.camera, *in.mesh);
    glUniformMatrix4fv(glGetUniformLocation(program_, "view_projection"), 1, GL_FALSE, vp.data());
    glUniform3fv(glGetUniformLocation(program_, "albedo"), 1, in.albedo.data());
    glUniform1i(glGetUniformLocation(program_, "only_cluster"), -1);
    constants_.bind(program_, "constants", 0);
    cluster_of_vertex_.bind(program_, "cluster_of_vertex", 1);
    weights_.bind(program_, "weights", 2);
    weight_index_.bind(program_, "weight_index", 3);
    vertex_colour_.bind(program_, "vertex_colour", 4);
    group_of_cluster_.bind(program_, "group_of_cluster", 5);
    exit_values_.bind(program_, "exit_values", 6);
    if (capture_) {
      // Each vertex shaded once (an indexed draw shades a vertex again for
      // every triangle corner that misses the driver's vertex cache), then
      // the triangles drawn with those colours.
      glEnable(GL_RASTERIZER_DISCARD);
      glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, captured_.buffer);
      glBeginTransformFeedback(GL_POINTS);
      glDrawArrays(GL_POINTS, 0, static_cast<GLsizei>(vertices_));
      glEndTransformFeedback();
      glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, 0);
      glDisable(GL_RASTERIZER_DISCARD);
      glUseProgram(plain_program_);
      glUniformMatrix4fv(glGetUniformLocation(plain_program_, "view_projection"), 1, GL_FALSE,
                         vp.data());
      captured_.bind(plain_program_, "vertex_colour", 4);
      draw_range(0, total_indices());
      return;
    }
    const bool layered = groups_.size() > 1;
    if (layered) {
      // Depth first, so the colour passes shade only the visible surface.
      glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
      glDepthFunc(GL_LESS);
      draw_range(groups_.front().first, total_indices());
      glDepthFunc(GL_LEQUAL);
      glDepthMask(GL_FALSE);
    }
    if (groups_.size() > 1) {
      glEnable(GL_BLEND);
      glBlendFunc(GL_ONE, GL_ONE);
    }
    const GLint only_cluster = glGetUniformLocation(program_, "only_cluster");
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    for (const Group& g : groups_) {
      glUniform1i(only_cluster, g.id);
      draw_range(g.first, g.count);
    }
    glDisable(GL_BLEND);
    glDepthMask(GL_TRUE);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  }

  std::size_t total_indices() const {
    std::size_t n = 0;
    for (const Group& g : groups_) n += g.count;
    return n;
  }
  void draw_range(std::size_t first, std::size_t count) {
    glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(count), GL_UNSIGNED_INT,
                   reinterpret_cast<const void*>(first * sizeof(std::uint32_t)));
  }

  Image read_image(const RenderInput& in) {
    std::vector<float> pixels(std::size_t(4) * width_ * height_);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
    glReadPixels(0, 0, width_, height_, GL_RGBA, GL_FLOAT, pixels.data());
    Image image(width_, height_);
    if (background_ && in.background) draw_environment(*in.background, in.camera, image);
    for (int y = 0; y < height_; ++y)
      for (int x = 0; x < width_; ++x) {
        const float* p =
            &pixels[4 * (std::size_t(height_ - 1 - y) * width_ + x)];  // GL rows bottom-up
        if (p[3] <= 0.f) continue;  // no triangle here: keep the background
        float* out = image.at(x, y);
        for (int c = 0; c < 3; ++c) out[c] = std::max(0.f, p[c]);
      }
    return image;
  }

  void release() {
    texel_draw_.release();
    if (vao_) glDeleteVertexArrays(1, &vao_);
    if (vertex_buffer_) glDeleteBuffers(1, &vertex_buffer_);
    if (index_buffer_) glDeleteBuffers(1, &index_buffer_);
    if (cluster_attribute_buffer_) glDeleteBuffers(1, &cluster_attribute_buffer_);
    if (weight_attribute_buffer_) glDeleteBuffers(1, &weight_attribute_buffer_);
    cluster_attribute_buffer_ = weight_attribute_buffer_ = 0;
    if (program_) glDeleteProgram(program_);
    if (plain_program_) glDeleteProgram(plain_program_);
    plain_program_ = 0;
    capture_ = false;
    for (TextureBuffer* b : {&constants_, &cluster_of_vertex_, &group_of_cluster_, &weights_,
                             &weight_index_, &vertex_colour_, &exit_values_, &captured_})
      b->release();
    vao_ = index_buffer_ = program_ = 0;
    vertex_buffer_ = 0;
  }

  struct Key {
    const Mesh* mesh = nullptr;
    std::size_t vertices = 0;
    const CompressedTransfer* transfer = nullptr;
    Eigen::Index dimension = 0;
    int components = 0;
    Eigen::Index clusters = 0;
    const float* weights = nullptr;
    std::size_t superclusters = 0;
    bool sparse = false;
    int rows = 0;
    bool per_cluster = false;
    bool operator==(const Key&) const = default;
  };
  struct Group {
    int id;  // cluster or supercluster; -1: everything at once
    std::size_t first, count;
  };

  bool per_cluster_, background_;
  std::unique_ptr<OffscreenContext> context_;
  int width_ = 0, height_ = 0;
  GLuint framebuffer_ = 0, renderbuffers_[2] = {0, 0};
  GLuint vao_ = 0, vertex_buffer_ = 0, index_buffer_ = 0, program_ = 0;
  // Single-pass drawing: program_ writes each vertex's colour to captured_,
  // which plain_program_ then draws.
  bool capture_ = false;
  GLuint plain_program_ = 0;
  TextureBuffer captured_;
  std::size_t vertices_ = 0;
  GLuint cluster_attribute_buffer_ = 0, weight_attribute_buffer_ = 0;
  // Locations 2..15 (position 0, cluster 1): n' <= 56 weights as attributes.
  static constexpr int kMaxWeightVec4s = 14;
  TextureBuffer constants_, cluster_of_vertex_, group_of_cluster_, weights_, weight_index_,
      vertex_colour_, exit_values_;
  std::vector<Group> groups_;
  TexelDraw texel_draw_;
  Key key_;
  std::map<std::string, double> stats_;
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::OpenGLRenderer, "opengl")
