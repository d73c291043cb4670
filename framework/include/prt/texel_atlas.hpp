// Texel receivers: transfer at the texels of a mesh's UV atlas (like D3DX9's
// per-texel PRT), and the radiance texture a renderer looks up.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "prt/mesh.hpp"

namespace prt {

// Which texels of a width x height texture hold transfer: one per row, as
// y * width + x, ascending. Texel (x, y) covers uv [x, x+1] / width x [y, y+1] / height.
struct TexelAtlas {
  int width = 0, height = 0;
  std::vector<std::uint32_t> texels;
};

// The texels of `mesh`'s atlas (Mesh::uvs) at resolution x resolution, and
// their surface points (positions and interpolated normals, no triangles).
// A texel is kept when its square meets a triangle in uv (texels outside
// every chart are skipped); its point is the point of the nearest triangle
// nearest to the texel's centre, so the texels along a chart's border, which
// a bilinear lookup reads, hold that chart's transfer.
struct TexelSamples {
  TexelAtlas atlas;
  Mesh points;
  std::size_t border = 0;  // texels whose centre lies outside every chart
};
// Throws prt::Error naming `source` when the mesh has no uvs, uvs outside
// [0, 1], or an atlas that overlaps itself (one texel inside two triangles
// at different places on the surface).
TexelSamples texel_samples(const Mesh& mesh, int resolution, const std::string& source);

// Throws prt::Error unless the atlas is consistent: positive sizes, texels
// in range and ascending; `source` names it.
void check_texel_atlas(const TexelAtlas& atlas, const std::string& source);

// Radiance per texel, looked up bilinearly (clamped to the texture's edge).
struct RadianceTexture {
  int width = 0, height = 0;
  std::vector<Eigen::Vector3f> texels;  // width x height, row y at y * width
  Eigen::Vector3f lookup(const Eigen::Vector2f& uv) const;
};

// Texels dilated past the charts' borders (each pass fills an empty texel
// beside a filled one with the mean of its filled neighbours), so a
// bilinear lookup at a seam never reads an empty texel.
constexpr int kTexelDilation = 2;

// The texture of `rows` (one radiance per atlas texel), dilated.
RadianceTexture radiance_texture(const TexelAtlas& atlas, const Eigen::MatrixX3f& rows,
                                 int dilation = kTexelDilation);

}  // namespace prt
