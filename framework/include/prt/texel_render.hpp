// What a renderer draws from its input: the radiance of each row, and for
// per-texel transfer the radiance texture.
#pragma once
#include "prt/renderer.hpp"
#include "prt/texel_atlas.hpp"

namespace prt {

// One radiance per row of `in` (a vertex, or a texel): vertex_radiance, or
// the transfer relit under its light; albedo applied and clamped at zero
// (negative ringing is not light). `renderer` names the caller in errors.
Eigen::MatrixX3f input_radiance(const RenderInput& in, const char* renderer);

// The texture of a per-texel render input (RenderInput::texels): its rows
// (vertex_radiance, or the transfer relit under its light), albedo applied,
// clamped at zero (negative ringing is not light), dilated past the charts.
// Throws prt::Error when the rows do not match the atlas or the mesh has no uvs.
RadianceTexture texel_texture(const RenderInput& in, const char* renderer);

}  // namespace prt
