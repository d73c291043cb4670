// Every key of a scene's sections, each declared once: its schema record (the
// scene reader checks keys, types and ranges against it) and its typed reader
// (`keys::transport::bounces(scene.transport)`). prt/plugin.hpp's param::
// declarations; plug-ins declare theirs the same way.
#pragma once
#include "prt/glossy.hpp"
#include "prt/plugin.hpp"

namespace prt::keys {

inline constexpr double kBig = schema::kHuge;

namespace mesh {
inline constexpr auto file =
    param::path("file", false, "mesh file (OFF, OBJ, PLY, STL), relative to the scene");
inline constexpr auto generate = param::choice("generate", "", "sphere|plane|box|open-box|room",
                                               "a generated mesh instead of a file");
inline constexpr auto detail =
    param::integer("detail", "3", 0, 8, "subdivision level of a generated mesh");
}  // namespace mesh

// A mesh the scene places: each [[mesh.add]] (joined to the scene's mesh)
// and [moving] (the object shaded from probes).
namespace place {
inline constexpr auto file =
    param::path("file", false, "mesh file (OFF, OBJ, PLY, STL), relative to the scene");
inline constexpr auto generate = param::choice("generate", "", "sphere|plane|box|open-box|room",
                                               "a generated mesh instead of a file");
inline constexpr auto detail =
    param::integer("detail", "3", 0, 8, "subdivision level of a generated mesh");
inline constexpr auto position = param::reals("position", "0,0,0", 3, -kBig, kBig,
                                              "where the bottom centre of the mesh's bounds goes");
inline constexpr auto size =
    param::real("size", "1", 1e-9, kBig, "the longest side of the mesh's bounds, scene units");
}  // namespace place

namespace receivers {
inline constexpr auto kind =
    param::choice("kind", "vertices", "vertices|texels|probes",
                  "where transfer is computed: the mesh's vertices, the texels of its atlas, "
                  "or probes on a grid");
inline constexpr auto resolution = param::integer(
    "resolution", "64", 1, 8192, "texels: the atlas texture's width and height in texels");
inline constexpr auto spacing =
    param::real("spacing", "0.5", 1e-6, kBig, "probes: distance between neighbouring probes");
inline constexpr auto interpolation = param::choice(
    "interpolation", "visibility", "visibility|trilinear",
    "probes: trilinear weights of the 8 probes around a point, with (visibility) or without "
    "(trilinear) the leak control: invalid probes and probes the point cannot see drop out");
inline constexpr auto normal_bias = param::real(
    "normal_bias", "0.25", 0, 2,
    "probes, visibility: the shaded point moves this many spacings along its normal first");
inline constexpr auto invalid_fraction = param::real(
    "invalid_fraction", "0.25", 0, 1,
    "probes: a probe whose rays hit back faces more often than this is inside geometry");
}  // namespace receivers

namespace material {
inline constexpr auto albedo =
    param::reals("albedo", "0.8", 3, 0, 1, "RGB tint of the whole reflectance (RGB or grey)");
inline constexpr auto brdf =
    param::choice("brdf", "lambert", "lambert|phong|ward|cook-torrance",
                  "reflectance model: lambert bakes vectors, the others glossy matrices");
inline constexpr auto diffuse =
    param::reals("diffuse", "1", 3, 0, 1, "kd: weight of the Lambertian part (RGB or grey)");
inline constexpr auto specular =
    param::reals("specular", "0.5", 3, 0, 1, "ks: weight of the glossy lobe (RGB or grey)");
// Lobe limits: the BRDF matrix's 48 x 98 quadrature resolves them (and
// order-5..12 SH cannot hold sharper lobes anyway).
inline constexpr auto exponent = param::real("exponent", "32", 0, 1000, "phong: lobe exponent");
inline constexpr auto anisotropic_roughness =
    param::reals("anisotropic_roughness", "0.1,0.3", 2, 0.03, 10,
                 "ward: roughness along the tangent and the bitangent");
inline constexpr auto roughness =
    param::real("roughness", "0.3", 0.03, 10, "cook-torrance: Beckmann slope m");
inline constexpr auto fresnel =
    param::real("fresnel", "0.04", 0, 1, "cook-torrance: Schlick reflectance at normal incidence");
inline constexpr auto incident_order =
    param::integer("incident_order", "0", 0, kMaxIncidentOrder,
                   "glossy: SH order M the BRDF is band-limited to in its incident direction (0: "
                   "the light basis's band count when it has bands, else 8)");
inline constexpr auto projection = param::choice(
    "projection", "least-squares", "least-squares|zero",
    "glossy: hemispherical projection of the BRDF's incident side ([exit] has its own)");
inline constexpr auto cutoff =
    param::real("cutoff", "1e-10", 0, 1,
                "glossy least squares: singular values of A below this x the largest are dropped");
inline constexpr auto subsurface =
    param::boolean("subsurface", "false", "add Jensen-Buhler multiple scattering");
inline constexpr auto sigma_a = param::reals(
    "sigma_a", "0.0041", 3, 1e-9, 1e6, "subsurface: absorption coefficient, 1/mm (RGB or grey)");
inline constexpr auto sigma_s =
    param::reals("sigma_s", "2.62", 3, 1e-9, 1e6,
                 "subsurface: reduced scattering coefficient, 1/mm (RGB or grey)");
inline constexpr auto preset = param::choice(
    "preset", "",
    "apple|chicken1|chicken2|cream|ketchup|marble|potato|skimmilk|skin1|skin2|wholemilk",
    "subsurface: Jensen et al. 2001's measured sigma_a and sigma_s (RGB) and eta 1.3, "
    "instead of those keys");
inline constexpr auto eta =
    param::real("eta", "1.5", 1.0, 4.0, "subsurface: relative index of refraction");
inline constexpr auto mm_per_unit =
    param::real("mm_per_unit", "100", 1e-9, 1e9, "subsurface: millimetres per mesh unit");
inline constexpr auto subsurface_error =
    param::real("subsurface_error", "0.3", 0, 10,
                "subsurface hierarchy: group radius / distance below which a group is one point");
}  // namespace material

namespace transport {
inline constexpr auto directions =
    param::choice("directions", "fibonacci", "fibonacci|stratified|cubemap", "direction set");
inline constexpr auto rays =
    param::integer("rays", "1024", 1, 4194304, "directions per vertex over the sphere");
inline constexpr auto shadowed =
    param::boolean("shadowed", "true", "trace visibility (false: unshadowed transfer)");
inline constexpr auto bounces = param::integer(
    "bounces", "0", 0, 64,
    "inter-reflection bounces (diffuse or glossy) gathered from the shadow rays' hits");
inline constexpr auto seed =
    param::integer("seed", "1", 0, 9.2e18, "seed of stratified directions");
}  // namespace transport

namespace lighting {
inline constexpr auto environment =
    param::path("environment", false, "equirectangular environment map (.exr or .hdr)");
inline constexpr auto constant =
    param::reals("constant", "", 3, 0, kBig, "constant radiance instead of a map");
inline constexpr auto intensity = param::real("intensity", "1", 0, kBig, "radiance scale");
inline constexpr auto rotation =
    param::real("rotation", "0", -3600, 3600, "rotation of the environment about +y, degrees");
inline constexpr auto window =
    param::choice("window", "none", "none|hanning|lanczos",
                  "SH bases: sigma factors on the light's bands against ringing (negative light)");
inline constexpr auto nearest =
    param::integer("nearest", "1", 1, 64,
                   "point lights on a lattice basis (eigen, haar): lattice directions nearest to "
                   "the light that share it (k)");
}  // namespace lighting

namespace point {
inline constexpr auto position =
    param::reals("position", "", 3, -kBig, kBig, "the light's position (mesh units)");
inline constexpr auto colour = param::reals("colour", "1", 3, 0, kBig, "RGB colour (RGB or grey)");
inline constexpr auto intensity =
    param::real("intensity", "1", 0, kBig,
                "exit radiance of a lit white vertex facing it is intensity / pi (no falloff)");
inline constexpr auto radius =
    param::real("radius", "0", 0, kBig, "radius of a spherical light (0: an ideal point)");
}  // namespace point

namespace camera {
inline constexpr auto position =
    param::reals("position", "", 3, -kBig, kBig, "eye position (default: frames the mesh)");
inline constexpr auto target =
    param::reals("target", "", 3, -kBig, kBig, "point looked at (default: mesh centre)");
inline constexpr auto up = param::reals("up", "0,1,0", 3, -kBig, kBig, "up vector");
inline constexpr auto fov = param::real("fov", "40", 1, 170, "vertical field of view, degrees");
inline constexpr auto width = param::integer("width", "640", 1, 16384, "image width");
inline constexpr auto height = param::integer("height", "480", 1, 16384, "image height");
inline constexpr auto exposure =
    param::real("exposure", "1", 1e-6, 1e6, "scale applied to radiance before sRGB encoding");
}  // namespace camera

namespace output {
inline constexpr auto bake = param::text("bake", "", "bake file (.h5), relative to the scene");
inline constexpr auto image =
    param::text("image", "", "rendered image (.png), relative to the scene");
}  // namespace output

namespace ground_truth {
inline constexpr auto samples =
    param::integer("samples", "1024", 1, 1048576, "Monte Carlo samples per vertex");
inline constexpr auto seed = param::integer("seed", "7", 0, 9.2e18, "sampling seed");
}  // namespace ground_truth

}  // namespace prt::keys
