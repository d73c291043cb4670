// Exposure and the sRGB transfer curve, as prt::write_png applies them.
in vec2 uv;
uniform sampler2D image;  // linear radiance, top row first
uniform float exposure;
out vec4 colour;
void main() {
  vec3 c = clamp(texture(image, uv).rgb * exposure, 0.0, 1.0);
  vec3 srgb = mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
  colour = vec4(srgb, 1.0);
}
