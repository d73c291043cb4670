// Texel receivers: the atlas rasterised into texel points, and the radiance
// texture renderers look up.
#include "prt/texel_atlas.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "prt/error.hpp"

namespace prt {

namespace {

// The point of triangle (a, b, c) nearest to p, as barycentrics (of b and c),
// and its squared distance: a 2-D closest-point test by the triangle's regions.
struct Nearest {
  float distance2 = std::numeric_limits<float>::max();
  float u = 0, v = 0;  // weights of b and c
};

Nearest nearest_on_segment(const Eigen::Vector2f& p, const Eigen::Vector2f& a,
                           const Eigen::Vector2f& b, float& t) {
  const Eigen::Vector2f ab = b - a;
  const float length2 = ab.squaredNorm();
  t = length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.f, 1.f) : 0.f;
  Nearest n;
  n.distance2 = (a + t * ab - p).squaredNorm();
  return n;
}

Nearest nearest_in_triangle(const Eigen::Vector2f& p, const Eigen::Vector2f& a,
                            const Eigen::Vector2f& b, const Eigen::Vector2f& c) {
  const float area = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
  if (area != 0) {
    const float u = ((p - a).x() * (c - a).y() - (p - a).y() * (c - a).x()) / area;
    const float v = ((b - a).x() * (p - a).y() - (b - a).y() * (p - a).x()) / area;
    if (u >= 0 && v >= 0 && u + v <= 1) return {0, u, v};
  }
  float t = 0;
  Nearest best = nearest_on_segment(p, a, b, t);
  best.u = t, best.v = 0;
  Nearest edge = nearest_on_segment(p, a, c, t);
  if (edge.distance2 < best.distance2) best = {edge.distance2, 0, t};
  edge = nearest_on_segment(p, b, c, t);
  if (edge.distance2 < best.distance2) best = {edge.distance2, 1 - t, t};
  return best;
}

struct Claim {
  float distance2 = std::numeric_limits<float>::max();
  std::uint32_t triangle = 0;
  float u = 0, v = 0;
};

Eigen::Vector3f point_of(const Mesh& mesh, const Claim& c) {
  const auto& t = mesh.triangles[c.triangle];
  return (1 - c.u - c.v) * mesh.positions[t[0]] + c.u * mesh.positions[t[1]] +
         c.v * mesh.positions[t[2]];
}

Eigen::Vector3f normal_of(const Mesh& mesh, const Claim& c) {
  const auto& t = mesh.triangles[c.triangle];
  Eigen::Vector3f n =
      (1 - c.u - c.v) * mesh.normals[t[0]] + c.u * mesh.normals[t[1]] + c.v * mesh.normals[t[2]];
  if (n.norm() < 1e-12f)  // opposite normals cancel: the face's own
    n = (mesh.positions[t[1]] - mesh.positions[t[0]])
            .cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
  return n.normalized();
}

void check_uvs(const Mesh& mesh, const std::string& source) {
  if (mesh.uvs.size() != mesh.positions.size())
    throw Error(source + ": the mesh has no texture coordinates (an atlas) for texel receivers");
  for (std::size_t v = 0; v < mesh.uvs.size(); ++v) {
    const Eigen::Vector2f& uv = mesh.uvs[v];
    if (!(uv.minCoeff() >= -1e-4f && uv.maxCoeff() <= 1 + 1e-4f))
      throw Error(source + ": vertex " + std::to_string(v) + " has texture coordinates (" +
                  std::to_string(uv.x()) + ", " + std::to_string(uv.y()) +
                  ") outside [0, 1]: texel receivers need an atlas in the unit square (no "
                  "tiling)");
  }
}

// Every texel's nearest triangle within half a texel's diagonal; counts the
// texels inside two triangles that lie at different places (an overlap).
std::vector<Claim> claim_texels(const Mesh& mesh, int resolution, std::size_t& overlaps,
                                std::size_t& first_overlap) {
  const float r = float(resolution), reach2 = 0.5f + 1e-4f;  // (sqrt(2) / 2)^2 texels^2
  const float apart = 1e-3f * (mesh.bounds_max() - mesh.bounds_min()).norm();
  std::vector<Claim> claims(std::size_t(resolution) * resolution);
  std::vector<std::uint8_t> overlapped(claims.size(), 0);
  overlaps = 0;
  for (std::uint32_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    const Eigen::Vector2f a = mesh.uvs[t[0]] * r, b = mesh.uvs[t[1]] * r, c = mesh.uvs[t[2]] * r;
    const Eigen::Vector2f lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
    const int x0 = std::max(0, int(std::floor(lo.x() - 1))),
              y0 = std::max(0, int(std::floor(lo.y() - 1)));
    const int x1 = std::min(resolution - 1, int(std::ceil(hi.x()))),
              y1 = std::min(resolution - 1, int(std::ceil(hi.y())));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const Nearest n = nearest_in_triangle({x + 0.5f, y + 0.5f}, a, b, c);
        if (n.distance2 > reach2) continue;
        Claim& claim = claims[std::size_t(y) * resolution + x];
        const Claim mine{n.distance2, f, n.u, n.v};
        const std::size_t texel = std::size_t(y) * resolution + x;
        if (n.distance2 == 0 && claim.distance2 == 0 && !overlapped[texel] &&
            (point_of(mesh, claim) - point_of(mesh, mine)).norm() > apart) {
          if (overlaps++ == 0) first_overlap = texel;
          overlapped[texel] = 1;
        }
        if (n.distance2 < claim.distance2) claim = mine;
      }
  }
  return claims;
}

}  // namespace

TexelSamples texel_samples(const Mesh& mesh, int resolution, const std::string& source) {
  check_uvs(mesh, source);
  if (resolution < 1 || resolution > 16384)
    throw Error(source + ": texel resolution " + std::to_string(resolution) +
                " is outside [1, 16384]");
  std::size_t overlaps = 0, first = 0;
  const std::vector<Claim> claims = claim_texels(mesh, resolution, overlaps, first);
  if (overlaps > 0)
    throw Error(source + ": the mesh's atlas overlaps itself: " + std::to_string(overlaps) +
                " texel(s) at resolution " + std::to_string(resolution) +
                " lie inside two triangles at different places (the first at texel (" +
                std::to_string(first % resolution) + ", " + std::to_string(first / resolution) +
                ")); texel receivers need each texel on one surface (no mirrored or shared "
                "charts)");
  TexelSamples out;
  out.atlas.width = out.atlas.height = resolution;
  for (std::size_t i = 0; i < claims.size(); ++i) {
    if (claims[i].distance2 == std::numeric_limits<float>::max()) continue;
    out.atlas.texels.push_back(std::uint32_t(i));
    out.border += claims[i].distance2 > 0;
    out.points.positions.push_back(point_of(mesh, claims[i]));
    out.points.normals.push_back(normal_of(mesh, claims[i]));
  }
  if (out.atlas.texels.empty())
    throw Error(source + ": no texel of the atlas lies on a triangle at resolution " +
                std::to_string(resolution));
  return out;
}

void check_texel_atlas(const TexelAtlas& atlas, const std::string& source) {
  if (atlas.width < 1 || atlas.height < 1 || atlas.width > 16384 || atlas.height > 16384)
    throw Error(source + ": texel atlas of " + std::to_string(atlas.width) + " x " +
                std::to_string(atlas.height) + " texels is out of range");
  const std::size_t count = std::size_t(atlas.width) * atlas.height;
  for (std::size_t i = 0; i < atlas.texels.size(); ++i)
    if (atlas.texels[i] >= count || (i > 0 && atlas.texels[i] <= atlas.texels[i - 1]))
      throw Error(source + ": texel " + std::to_string(i) + " (" + std::to_string(atlas.texels[i]) +
                  ") is out of range or out of order");
}

Eigen::Vector3f RadianceTexture::lookup(const Eigen::Vector2f& uv) const {
  const float fx = std::clamp(uv.x() * width - 0.5f, 0.f, float(width - 1));
  const float fy = std::clamp(uv.y() * height - 0.5f, 0.f, float(height - 1));
  const int x0 = int(fx), y0 = int(fy);
  const int x1 = std::min(x0 + 1, width - 1), y1 = std::min(y0 + 1, height - 1);
  const float tx = fx - x0, ty = fy - y0;
  const auto at = [&](int x, int y) { return texels[std::size_t(y) * width + x]; };
  return (1 - ty) * ((1 - tx) * at(x0, y0) + tx * at(x1, y0)) +
         ty * ((1 - tx) * at(x0, y1) + tx * at(x1, y1));
}

RadianceTexture radiance_texture(const TexelAtlas& atlas, const Eigen::MatrixX3f& rows,
                                 int dilation) {
  if (rows.rows() != Eigen::Index(atlas.texels.size()))
    throw Error("radiance texture: " + std::to_string(rows.rows()) + " radiance rows for " +
                std::to_string(atlas.texels.size()) + " texels");
  RadianceTexture texture;
  texture.width = atlas.width, texture.height = atlas.height;
  const std::size_t count = std::size_t(atlas.width) * atlas.height;
  texture.texels.assign(count, Eigen::Vector3f::Zero());
  std::vector<std::uint8_t> filled(count, 0);
  for (std::size_t i = 0; i < atlas.texels.size(); ++i) {
    texture.texels[atlas.texels[i]] = rows.row(Eigen::Index(i)).transpose();
    filled[atlas.texels[i]] = 1;
  }
  const int w = atlas.width, h = atlas.height;
  for (int pass = 0; pass < dilation; ++pass) {
    std::vector<std::uint8_t> next = filled;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const std::size_t i = std::size_t(y) * w + x;
        if (filled[i]) continue;
        Eigen::Vector3f sum = Eigen::Vector3f::Zero();
        int n = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
            const std::size_t j = std::size_t(ny) * w + nx;
            if (filled[j]) sum += texture.texels[j], ++n;
          }
        if (n > 0) texture.texels[i] = sum / float(n), next[i] = 1;
      }
    filled = std::move(next);
  }
  return texture;
}

}  // namespace prt
