// A full-screen triangle for showing the rendered image in the viewer window.
out vec2 uv;
void main() {
  vec2 corner = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
  uv = vec2(corner.x, 1.0 - corner.y);  // 0..1 over the visible part (corners run to 2)
  gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}
