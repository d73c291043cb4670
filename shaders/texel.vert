// Per-texel transfer (docs/receivers.md): positions and the atlas's uvs; the
// radiance is looked up in the fragment stage.
// The host prepends: #version.

layout(location = 0) in vec3 position;
layout(location = 1) in vec2 uv;

uniform mat4 view_projection;

invariant gl_Position;

out vec2 texel_uv;

void main() {
  gl_Position = view_projection * vec4(position, 1.0);
  texel_uv = uv;
}
