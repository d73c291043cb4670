#include "prt/texel_render.hpp"

#include "prt/error.hpp"
#include "prt/relight.hpp"

namespace prt {

Eigen::MatrixX3f input_radiance(const RenderInput& in, const char* renderer) {
  Eigen::MatrixX3f rows;
  if (in.vertex_radiance)
    rows = *in.vertex_radiance;
  else if (in.transfer)
    rows = relight(*in.transfer, in.light, in.exit_values);
  else
    throw Error(std::string(renderer) + " renderer: neither transfer nor vertex radiance given");
  for (int c = 0; c < 3; ++c) rows.col(c) *= in.albedo[c];
  return rows.cwiseMax(0.f);
}

RadianceTexture texel_texture(const RenderInput& in, const char* renderer) {
  const std::string who = std::string(renderer) + " renderer: ";
  if (!in.texels || !in.mesh) throw Error(who + "no texel atlas or mesh");
  if (in.mesh->uvs.size() != in.mesh->vertex_count())
    throw Error(who + "per-texel radiance needs the mesh's texture coordinates");
  const Eigen::MatrixX3f rows = input_radiance(in, renderer);
  if (rows.rows() != Eigen::Index(in.texels->texels.size()))
    throw Error(who + std::to_string(rows.rows()) + " radiance rows for " +
                std::to_string(in.texels->texels.size()) + " texels");
  return radiance_texture(*in.texels, rows);
}

}  // namespace prt
