// The radiance texture of per-texel transfer, looked up bilinearly (GL_LINEAR,
// clamped to the edge) at the fragment's perspective-correct uv: the CPU
// renderer's RadianceTexture::lookup. Albedo is applied and the texture
// dilated past the charts on the CPU (prt/texel_atlas.hpp).
// The host prepends: #version.

in vec2 texel_uv;
uniform sampler2D radiance;  // RGB32F
out vec4 fragment;

void main() {
  fragment = vec4(texture(radiance, texel_uv).rgb, 1.0);
}
