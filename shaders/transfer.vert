// Per-vertex weighted sums of per-cluster constants (Sloan 2003 §6):
//   e_p = C[k][0] + sum_i w_pi C[k][i]
// C (computed on the CPU when the light changes) holds, per cluster, (n' + 1)
// groups of ROWS RGB texels; the weights come from a buffer indexed by the
// vertex. Diffuse transfer (ROWS == 1) has e_p as its radiance; glossy
// transfer has ROWS exit coefficients per colour, dotted with the exit basis's
// values toward the camera (exit_values, ROWS per vertex, updated with the
// view on the CPU by the exit plug-in, so any exit basis works).
// Where n' allows (ATTRIBUTES), the cluster index and the weights arrive as
// vertex attributes instead of buffer fetches.
// Single-pass drawing runs this stage once per vertex (CAPTURE: points with
// transform feedback into `captured`), then draws the triangles with the
// captured colours as a plain vertex-colour draw: an indexed draw would run
// it again for every triangle corner its vertex cache misses.
// The host prepends: #version, ROWS, COMPONENTS, SPARSE, GLOSSY, ATTRIBUTES,
// WEIGHT_VEC4S, CAPTURE.

layout(location = 0) in vec3 position;
#if ATTRIBUTES
layout(location = 1) in int cluster_attribute;
#if COMPONENTS > 0
layout(location = 2) in vec4 weight_attribute[WEIGHT_VEC4S];
#endif
#endif

uniform mat4 view_projection;
uniform vec3 albedo;
uniform int only_cluster;  // per-cluster drawing: the group drawn in this pass, or -1

uniform samplerBuffer constants;          // RGBA32F, rgb used
uniform isamplerBuffer cluster_of_vertex;  // R32I
uniform isamplerBuffer group_of_cluster;   // R32I: cluster, or its supercluster
uniform samplerBuffer weights;            // R32F, COMPONENTS per vertex
uniform isamplerBuffer weight_index;       // R32I, sparse transfer only
uniform samplerBuffer vertex_colour;      // RGBA32F, plain colour draws (COMPONENTS < 0)
uniform samplerBuffer exit_values;        // R32F, glossy: ROWS per vertex

invariant gl_Position;

out vec3 colour;
#if CAPTURE
out vec4 captured;
#endif

void shade();

void main() {
  shade();
#if CAPTURE
  captured = vec4(colour, 1.0);
#endif
}

void shade() {
  gl_Position = view_projection * vec4(position, 1.0);
  int v = gl_VertexID;
#if COMPONENTS < 0
  colour = texelFetch(vertex_colour, v).rgb;
#else
#if ATTRIBUTES
  int k = cluster_attribute;
#else
  int k = texelFetch(cluster_of_vertex, v).r;
#endif
  // Partition of unity for per-cluster drawing: other clusters' vertices add 0.
  float member =
      (only_cluster < 0 || texelFetch(group_of_cluster, k).r == only_cluster) ? 1.0 : 0.0;
#if SPARSE
  // Non-linear approximation: constants = [mean . l, l_0, l_1, ...].
  vec3 e = texelFetch(constants, 0).rgb;
  for (int j = 0; j < COMPONENTS; ++j)
    e += texelFetch(weights, v * COMPONENTS + j).r *
         texelFetch(constants, 1 + texelFetch(weight_index, v * COMPONENTS + j).r).rgb;
  colour = member * max(albedo * e, vec3(0.0));
#else
  int base = k * (COMPONENTS + 1) * ROWS;
  float w[COMPONENTS + 1];
  w[0] = 1.0;
#if ATTRIBUTES && COMPONENTS > 0
  for (int i = 0; i < COMPONENTS; ++i) w[i + 1] = weight_attribute[i / 4][i % 4];
#else
  for (int i = 0; i < COMPONENTS; ++i) w[i + 1] = texelFetch(weights, v * COMPONENTS + i).r;
#endif
#if GLOSSY
  vec3 e = vec3(0.0);
  for (int r = 0; r < ROWS; ++r) {
    vec3 row = vec3(0.0);
    for (int i = 0; i <= COMPONENTS; ++i) row += w[i] * texelFetch(constants, base + i * ROWS + r).rgb;
    e += texelFetch(exit_values, v * ROWS + r).r * row;
  }
  colour = member * max(albedo * e, vec3(0.0));
#else
  vec3 e = vec3(0.0);
  for (int i = 0; i <= COMPONENTS; ++i) e += w[i] * texelFetch(constants, base + i).rgb;
  colour = member * max(albedo * e, vec3(0.0));  // negative SH ringing is not light
#endif
#endif
#endif
}
