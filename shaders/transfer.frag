// Diffuse: the interpolated colour. Glossy: y(v_p) . e_p for one colour
// channel, with the real SH of the framework's conventions (index l(l+1)+m,
// no Condon-Shortley phase) evaluated by the same normalised recurrence.
// The host prepends: #version, ROWS, GLOSSY, ORDER.

#if GLOSSY
in float exit_radiance[ROWS];
in vec3 local_view;
uniform int kept[ROWS];  // SH index of each exit-basis function
uniform vec3 albedo;
uniform int channel;
uniform bool clamp_negative;
#else
in vec3 colour;
#endif
out vec4 fragment;

#if GLOSSY
void evaluate_sh(vec3 d, out float y[ORDER * ORDER]) {
  float q_mm = 0.28209479177387814;  // 1 / sqrt(4 pi)
  float c = 1.0, s = 0.0;            // Re, Im of (x + iy)^m
  for (int m = 0; m < ORDER; ++m) {
    if (m > 0) {
      q_mm *= sqrt((2.0 * float(m) + 1.0) / (2.0 * float(m)));
      float c_next = c * d.x - s * d.y;
      s = c * d.y + s * d.x;
      c = c_next;
    }
    float scale_cos = m == 0 ? 1.0 : 1.4142135623730951 * c;
    float scale_sin = 1.4142135623730951 * s;
    float q_prev = 0.0, q = q_mm;
    for (int l = m; l < ORDER; ++l) {
      if (l == m + 1) {
        q_prev = q;
        q = sqrt(2.0 * float(m) + 3.0) * d.z * q_mm;
      } else if (l > m + 1) {
        float ll = float(l), mm = float(m);
        float a = sqrt((4.0 * ll * ll - 1.0) / (ll * ll - mm * mm));
        float b = sqrt(((ll - 1.0) * (ll - 1.0) - mm * mm) / (4.0 * (ll - 1.0) * (ll - 1.0) - 1.0));
        float next = a * (d.z * q - b * q_prev);
        q_prev = q;
        q = next;
      }
      y[l * (l + 1) + m] = q * scale_cos;
      if (m > 0) y[l * (l + 1) - m] = q * scale_sin;
    }
  }
}
#endif

void main() {
#if GLOSSY
  // The exit basis lives on the upper hemisphere: keep v just above it.
  vec3 v = local_view;
  v.z = max(v.z, 1e-3 * length(v));
  v = normalize(v);
  float y[ORDER * ORDER];
  evaluate_sh(v, y);
  float sum = 0.0;
  for (int r = 0; r < ROWS; ++r) sum += y[kept[r]] * exit_radiance[r];
  float value = albedo[channel] * sum;
  if (clamp_negative) value = max(value, 0.0);
  fragment = vec4(value, value, value, 1.0);
#else
  fragment = vec4(colour, 1.0);
#endif
}
