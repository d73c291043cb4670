// The colour interpolated from the vertices (diffuse or glossy alike: glossy
// exit radiance is evaluated per vertex, toward the camera, in the vertex
// stage).
// The host prepends: #version, ROWS, GLOSSY.

in vec3 colour;
out vec4 fragment;

void main() {
  fragment = vec4(colour, 1.0);
}
