// A software rasteriser: z-buffer, perspective-correct Gouraud interpolation
// of per-vertex colours, pixel centres at (x + 0.5, y + 0.5) as in OpenGL.
#pragma once
#include <Eigen/Core>
#include <functional>
#include <vector>

#include "prt/camera.hpp"
#include "prt/image.hpp"
#include "prt/mesh.hpp"
#include "prt/transfer.hpp"

namespace prt {

// Turns perspective-correct interpolated vertex attributes into an RGB pixel.
using PixelShader = std::function<void(const float* attributes, float* rgb)>;

// Draws the mesh with per-vertex attributes (v x k, row-major) shaded per
// pixel into `image`; returns the coverage mask (1 where a triangle was drawn).
std::vector<std::uint8_t> rasterize(const Mesh& mesh, const MatrixXfRow& attributes,
                                    const Camera& camera, Image& image, const PixelShader& shade);

// Gouraud shading: the attributes are RGB colours.
std::vector<std::uint8_t> rasterize(const Mesh& mesh, const Eigen::MatrixX3f& vertex_colours,
                                    const Camera& camera, Image& image);

}  // namespace prt
