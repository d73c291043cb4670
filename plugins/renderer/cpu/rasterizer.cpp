#include "rasterizer.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

namespace prt {

std::vector<std::uint8_t> rasterize(const Mesh& mesh, const Eigen::MatrixX3f& colours,
                                    const Camera& camera, Image& image) {
  const MatrixXfRow attributes = colours;
  return rasterize(mesh, attributes, camera, image, [](const float* colour, float* rgb) {
    for (int c = 0; c < 3; ++c) rgb[c] = colour[c];
  });
}

std::vector<std::uint8_t> rasterize(const Mesh& mesh, const MatrixXfRow& attributes,
                                    const Camera& camera, Image& image, const PixelShader& shade) {
  const int W = image.width, H = image.height;
  const Eigen::Matrix4f vp = view_projection(camera, mesh);
  // Screen position (x, y in pixels, z in [0,1]) and 1/w per vertex.
  std::vector<Eigen::Vector4f> screen(mesh.vertex_count());
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const Eigen::Vector4f clip = vp * mesh.positions[v].homogeneous();
    const float inv_w = clip.w() > 1e-8f ? 1.f / clip.w() : -1.f;
    screen[v] = {(clip.x() * inv_w * 0.5f + 0.5f) * W, (0.5f - clip.y() * inv_w * 0.5f) * H,
                 clip.z() * inv_w * 0.5f + 0.5f, inv_w};
  }
  std::vector<float> depth(static_cast<std::size_t>(W) * H, std::numeric_limits<float>::max());
  std::vector<std::uint8_t> covered(static_cast<std::size_t>(W) * H, 0);
  constexpr int kBand = 16;  // rows per task; each task owns its rows, so no locking
  const Eigen::Index k = attributes.cols();
  tbb::parallel_for(0, (H + kBand - 1) / kBand, [&](int band) {
    Eigen::RowVectorXf interpolated(k);
    const int row_begin = band * kBand, row_end = std::min(H, row_begin + kBand);
    for (const auto& t : mesh.triangles) {
      const Eigen::Vector4f& a = screen[t[0]];
      const Eigen::Vector4f& b = screen[t[1]];
      const Eigen::Vector4f& c = screen[t[2]];
      if (a.w() <= 0 || b.w() <= 0 || c.w() <= 0) continue;  // behind the eye
      const float area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
      if (std::abs(area) < 1e-12f) continue;
      const int x0 = std::max(0, int(std::floor(std::min({a.x(), b.x(), c.x()}))));
      const int x1 = std::min(W - 1, int(std::ceil(std::max({a.x(), b.x(), c.x()}))));
      const int y0 = std::max(row_begin, int(std::floor(std::min({a.y(), b.y(), c.y()}))));
      const int y1 = std::min(row_end - 1, int(std::ceil(std::max({a.y(), b.y(), c.y()}))));
      for (int y = y0; y <= y1; ++y) {
        const float py = y + 0.5f;
        for (int x = x0; x <= x1; ++x) {
          const float px = x + 0.5f;
          float l0 = ((b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px)) / area;
          float l1 = ((c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px)) / area;
          float l2 = 1.f - l0 - l1;
          if (l0 < 0 || l1 < 0 || l2 < 0) continue;
          const float z = l0 * a.z() + l1 * b.z() + l2 * c.z();
          const std::size_t i = static_cast<std::size_t>(y) * W + x;
          if (z < 0.f || z > 1.f || z >= depth[i]) continue;
          depth[i] = z;
          covered[i] = 1;
          // Perspective-correct weights.
          const float p0 = l0 * a.w(), p1 = l1 * b.w(), p2 = l2 * c.w();
          const float sum = p0 + p1 + p2;
          interpolated =
              (p0 * attributes.row(t[0]) + p1 * attributes.row(t[1]) + p2 * attributes.row(t[2])) /
              sum;
          shade(interpolated.data(), image.at(x, y));
        }
      }
    }
  });
  return covered;
}

}  // namespace prt
