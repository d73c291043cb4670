#include "prt/scene.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "prt/environment.hpp"
#include "prt/glossy.hpp"
#include "prt/lattice_lighting.hpp"
#include "prt/mesh.hpp"
#include "prt/plugin.hpp"
#include "prt/registry.hpp"
#include "prt/sh.hpp"
#include "scene_ascii.hpp"
#include "toml_checked.hpp"

namespace prt {
namespace fs = std::filesystem;
using namespace prt::schema;

namespace {

constexpr double kBig = kHuge;

const ParamSchema& mesh_schema() {
  static const ParamSchema s{
      "section [mesh]",
      {path("file", false, "mesh file (OFF, OBJ, PLY, STL), relative to the scene"),
       choice("generate", "", "sphere|plane|box|open-box", "a generated mesh instead of a file"),
       integer("detail", "3", 0, 8, "subdivision level of a generated mesh")}};
  return s;
}
const ParamSchema& material_schema() {
  static const ParamSchema s{
      "section [material]",
      {reals("albedo", "0.8", 3, 0, 1, "RGB tint of the whole reflectance (RGB or grey)"),
       choice("brdf", "lambert", "lambert|phong|ward|cook-torrance",
              "reflectance model: lambert bakes vectors, the others glossy matrices"),
       reals("diffuse", "1", 3, 0, 1, "kd: weight of the Lambertian part (RGB or grey)"),
       reals("specular", "0.5", 3, 0, 1, "ks: weight of the glossy lobe (RGB or grey)"),
       // Lobe limits: the BRDF matrix's 48 x 98 quadrature resolves them (and
       // order-5..12 SH cannot hold sharper lobes anyway).
       real("exponent", "32", 0, 1000, "phong: lobe exponent"),
       reals("anisotropic_roughness", "0.1,0.3", 2, 0.03, 10,
             "ward: roughness along the tangent and the bitangent"),
       real("roughness", "0.3", 0.03, 10, "cook-torrance: Beckmann slope m"),
       real("fresnel", "0.04", 0, 1, "cook-torrance: Schlick reflectance at normal incidence"),
       integer("incident_order", "0", 0, kMaxIncidentOrder,
               "glossy: SH order M the BRDF is band-limited to in its incident direction (0: "
               "the light basis's band count when it has bands, else 8)"),
       choice("projection", "least-squares", "least-squares|zero",
              "glossy: hemispherical projection of the BRDF's incident side ([exit] has its own)"),
       real("cutoff", "1e-10", 0, 1,
            "glossy least squares: singular values of A below this x the largest are dropped"),
       boolean("subsurface", "false", "add Jensen-Buhler multiple scattering"),
       reals("sigma_a", "0.0041", 3, 1e-9, 1e6,
             "subsurface: absorption coefficient, 1/mm (RGB or grey)"),
       reals("sigma_s", "2.62", 3, 1e-9, 1e6,
             "subsurface: reduced scattering coefficient, 1/mm (RGB or grey)"),
       choice("preset", "",
              "apple|chicken1|chicken2|cream|ketchup|marble|potato|skimmilk|skin1|skin2|wholemilk",
              "subsurface: Jensen et al. 2001's measured sigma_a and sigma_s (RGB) and eta 1.3, "
              "instead of those keys"),
       real("eta", "1.5", 1.0, 4.0, "subsurface: relative index of refraction"),
       real("mm_per_unit", "100", 1e-9, 1e9, "subsurface: millimetres per mesh unit"),
       real("subsurface_error", "0.3", 0, 10,
            "subsurface hierarchy: group radius / distance below which a group is one point")}};
  return s;
}
const ParamSchema& transport_schema() {
  static const ParamSchema s{
      "section [transport]",
      {choice("directions", "fibonacci", "fibonacci|stratified|cubemap", "direction set"),
       integer("rays", "1024", 1, 4194304, "directions per vertex over the sphere"),
       boolean("shadowed", "true", "trace visibility (false: unshadowed transfer)"),
       integer("bounces", "0", 0, 64,
               "inter-reflection bounces (diffuse or glossy) gathered from the shadow rays' hits"),
       integer("seed", "1", 0, 9.2e18, "seed of stratified directions")}};
  return s;
}
const ParamSchema& lighting_schema() {
  static const ParamSchema s{
      "section [lighting]",
      {path("environment", false, "equirectangular environment map (.exr or .hdr)"),
       reals("constant", "", 3, 0, kBig, "constant radiance instead of a map"),
       real("intensity", "1", 0, kBig, "radiance scale"),
       real("rotation", "0", -3600, 3600, "rotation of the environment about +y, degrees"),
       choice("window", "none", "none|hanning|lanczos",
              "SH bases: sigma factors on the light's bands against ringing (negative light)"),
       integer("nearest", "1", 1, 64,
               "point lights on a lattice basis (eigen, haar): lattice directions nearest to "
               "the light that share it (k)")}};
  return s;
}
const ParamSchema& point_light_schema() {
  static const ParamSchema s{
      "[[lighting.point]]",
      {reals("position", "", 3, -kBig, kBig, "the light's position (mesh units)"),
       reals("colour", "1", 3, 0, kBig, "RGB colour (RGB or grey)"),
       real("intensity", "1", 0, kBig,
            "exit radiance of a lit white vertex facing it is intensity / pi (no falloff)"),
       real("radius", "0", 0, kBig, "radius of a spherical light (0: an ideal point)")}};
  return s;
}
const ParamSchema& camera_schema() {
  static const ParamSchema s{
      "section [camera]",
      {reals("position", "", 3, -kBig, kBig, "eye position (default: frames the mesh)"),
       reals("target", "", 3, -kBig, kBig, "point looked at (default: mesh centre)"),
       reals("up", "0,1,0", 3, -kBig, kBig, "up vector"),
       real("fov", "40", 1, 170, "vertical field of view, degrees"),
       integer("width", "640", 1, 16384, "image width"),
       integer("height", "480", 1, 16384, "image height"),
       real("exposure", "1", 1e-6, 1e6, "scale applied to radiance before sRGB encoding")}};
  return s;
}
const ParamSchema& output_schema() {
  static const ParamSchema s{"section [output]",
                             {text("bake", "", "bake file (.h5), relative to the scene"),
                              text("image", "", "rendered image (.png), relative to the scene")}};
  return s;
}
const ParamSchema& ground_truth_schema() {
  static const ParamSchema s{
      "section [ground_truth]",
      {integer("samples", "1024", 1, 1048576, "Monte Carlo samples per vertex"),
       integer("seed", "7", 0, 9.2e18, "sampling seed")}};
  return s;
}

const std::array<std::string, 11> kSections = {"mesh",   "material",   "transport",   "basis",
                                               "exit",   "compressor", "lighting",    "renderer",
                                               "camera", "output",     "ground_truth"};

SourceLocation location_of(const toml::source_region& region, const fs::path& file) {
  return {file.string(), static_cast<int>(region.begin.line),
          static_cast<int>(region.begin.column)};
}

ParamValue to_value(const toml::node& node, const SourceLocation& where, const std::string& key) {
  if (auto v = node.as_boolean()) return v->get();
  if (auto v = node.as_integer()) return v->get();
  if (auto v = node.as_floating_point()) return v->get();
  if (auto v = node.as_string()) return v->get();
  if (auto array = node.as_array()) {
    std::vector<double> values;
    for (const auto& item : *array) {
      if (auto i = item.as_integer())
        values.push_back(double(i->get()));
      else if (auto f = item.as_floating_point())
        values.push_back(f->get());
      else
        throw Error(where, "parameter \"" + key + "\": lists may hold only numbers");
    }
    return values;
  }
  throw Error(where, "parameter \"" + key + "\": tables and dates are not parameter values");
}

}  // namespace

// Here, beside the scene parser, so that both type values with the same toml++.
ParamValue parse_value(const std::string& text) {
  if (text.find_first_of("\n\r") == std::string::npos) {
    try {
      const toml::table table = toml::parse("value = " + text);
      if (table.size() == 1)
        if (const toml::node* node = table.get("value"))
          if (!node->is_table() && !node->is_date() && !node->is_time() && !node->is_date_time())
            return to_value(*node, SourceLocation{}, "value");
    } catch (const toml::parse_error&) {
    } catch (const Error&) {  // a list of non-numbers, a broken parser assumption
    }
  }
  return text;
}

void parse_assignment(const std::string& text, const SourceLocation& where, Params& params) {
  const auto equals = text.find('=');
  if (equals == std::string::npos || equals == 0)
    throw Error(where, "expected key=value, got \"" + text + "\"");
  params.set(text.substr(0, equals), parse_value(text.substr(equals + 1)), where);
}

namespace {

Params read_table(const toml::table* table, const SourceLocation& section_where,
                  const fs::path& file, const std::string& skip_key = "") {
  Params params(section_where);
  if (!table) return params;
  for (const auto& [key, node] : *table) {
    const std::string name(key.str());
    if (name == skip_key) continue;
    const SourceLocation where = location_of(key.source(), file);
    params.set(name, to_value(node, where, name), where);
  }
  return params;
}

// Resolves every path-typed parameter against the scene's folder and checks
// that the file exists, so missing files are reported before any work.
void resolve_paths(Params& params, const ParamSchema& schema, const SceneSpec& scene) {
  for (const auto& spec : schema.specs) {
    if (spec.type != ParamType::path || !params.has(spec.name)) continue;
    const std::string value = params.get_string(spec.name);
    if (value.empty()) continue;
    const fs::path resolved = scene.resolve(value);
    std::error_code error;
    const auto status = fs::status(resolved, error);
    if (!fs::exists(status))
      throw Error(params.location(spec.name), schema.owner + ": " + spec.name + " \"" + value +
                                                  "\" not found (looked for " + resolved.string() +
                                                  ")");
    if (!fs::is_regular_file(status))
      throw Error(params.location(spec.name),
                  schema.owner + ": " + spec.name + " \"" + value + "\" (" + resolved.string() +
                      ") is " + (fs::is_directory(status) ? "a directory" : "not a regular file") +
                      "; name a file");
    params.set(spec.name, resolved.string(), params.location(spec.name));
  }
}

PluginChoice read_plugin(const toml::table& root, const std::string& section,
                         const std::string& default_name, PluginKind kind,
                         const PluginRegistry& registry, const SceneSpec& scene) {
  PluginChoice choice;
  const toml::table* table = root[section].as_table();
  const SourceLocation section_where =
      table ? location_of(table->source(), scene.file) : SourceLocation{scene.file.string(), 1, 1};
  choice.where = section_where;
  choice.name = default_name;
  if (table) {
    if (const toml::node* plugin = table->get("plugin")) {
      choice.where = location_of(plugin->source(), scene.file);
      const auto name = plugin->value<std::string>();
      if (!name) throw Error(choice.where, "[" + section + "] plugin must be a string");
      choice.name = *name;
    }
  }
  choice.params = read_table(table, section_where, scene.file, "plugin");
  const PluginDescriptor& d = registry.find(kind, choice.name, choice.where);
  const ParamSchema schema = d.schema();
  choice.params.validate(schema);
  resolve_paths(choice.params, schema, scene);
  return choice;
}

}  // namespace

SceneSpec SceneSpec::load(const fs::path& file, const PluginRegistry& registry) {
  std::error_code error;
  const auto status = fs::status(file, error);
  if (!fs::exists(status)) throw Error(file.string() + ": scene file not found");
  if (!fs::is_regular_file(status))
    throw Error(file.string() + ": the scene is " +
                (fs::is_directory(status) ? "a directory" : "not a regular file") +
                "; name a .toml file");
  // A scene is a page of text; a huge file is a mistake (and toml++ would hold it all).
  constexpr std::uintmax_t kMaxSceneBytes = 16 << 20;
  if (fs::file_size(file, error) > kMaxSceneBytes)
    throw Error(file.string() + ": scene file larger than 16 MiB; is it a scene?");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw Error(file.string() + ": scene file unreadable");
  std::stringstream text;
  text << in.rdbuf();
  return parse(text.str(), file, registry);
}

void toml_assumption_broken(const char* what) {
  throw Error(std::string("malformed TOML (the parser's check \"") + what + "\" failed)");
}

namespace {

// [[lighting.point]]: an array of tables, each validated like a section.
std::vector<PointLight> read_point_lights(const toml::table* lighting, const fs::path& file) {
  std::vector<PointLight> lights;
  if (!lighting) return lights;
  const toml::node* node = lighting->get("point");
  if (!node) return lights;
  const toml::array* array = node->as_array();
  if (!array || !array->is_array_of_tables())
    throw Error(location_of(node->source(), file),
                "section [lighting]: \"point\" must be an array of tables, written "
                "[[lighting.point]] with position = [x, y, z] under it");
  for (const toml::node& item : *array) {
    const toml::table& table = *item.as_table();
    const SourceLocation where = location_of(table.source(), file);
    Params params = read_table(&table, where, file);
    params.validate(point_light_schema());
    if (!params.has("position")) throw Error(where, "[[lighting.point]]: \"position\" is required");
    PointLight light;
    light.position = Eigen::Vector3d(params.get_reals("position").data());
    light.colour = Eigen::Vector3d(params.get_reals("colour").data());
    light.intensity = params.get_real("intensity");
    light.radius = params.get_real("radius");
    lights.push_back(light);
  }
  return lights;
}

}  // namespace

namespace {

toml::table parse_toml(const std::string& text, const fs::path& file) {
  const std::string ascii = ascii_scene_text(text, file);
  try {
    return toml::parse(ascii, file.string());
  } catch (const toml::parse_error& e) {
    throw Error(location_of(e.source(), file), std::string(e.description()));
  } catch (const Error& e) {  // a broken parser assumption: no position is known
    throw Error(SourceLocation{file.string()}, e.what());
  }
}

void check_sections(const toml::table& root, const fs::path& file) {
  std::vector<std::string> valid(kSections.begin(), kSections.end());
  for (const auto& [key, node] : root) {
    const std::string name(key.str());
    const SourceLocation where = location_of(key.source(), file);
    if (std::find(valid.begin(), valid.end(), name) == valid.end()) {
      std::string message = "unknown section [" + elide(name) +
                            "]; valid: mesh, material, transport, "
                            "basis, compressor, lighting, renderer, camera, output, ground_truth";
      const std::string suggestion = closest_match(name, valid);
      if (!suggestion.empty()) message += " (did you mean [" + suggestion + "]?)";
      throw Error(where, message);
    }
    if (!node.is_table()) throw Error(where, "[" + name + "] must be a table");
  }
  // The exit basis was a set of [material] keys before it became a plug-in.
  if (const toml::table* material = root["material"].as_table())
    for (const char* old : {"exit_order", "exit_reduced"})
      if (const toml::node* node = material->get(old))
        throw Error(location_of(node->source(), file),
                    std::string("section [material]: \"") + old +
                        "\" is now a parameter of the exit basis: write [exit] plugin = \"hsh\", "
                        "order = 5, reduced = true");
}

Params read_section(const toml::table& root, const std::string& name, const ParamSchema& schema,
                    const SceneSpec& scene, const std::string& skip = "") {
  const toml::table* table = root[name].as_table();
  // A missing section's errors point at the file's start.
  const SourceLocation where = table ? location_of(table->source(), scene.file)
                                     : SourceLocation{scene.file.string(), 1, 1};
  Params params = read_table(table, where, scene.file, skip);
  params.validate(schema);
  resolve_paths(params, schema, scene);
  return params;
}

void read_sections(const toml::table& root, SceneSpec& scene) {
  scene.mesh = read_section(root, "mesh", mesh_schema(), scene);
  scene.material = read_section(root, "material", material_schema(), scene);
  if (!scene.material.get_string("preset").empty()) {  // measured coefficients replace the keys
    const toml::table* table = root["material"].as_table();
    for (const char* key : {"sigma_a", "sigma_s"})
      if (table->get(key))
        throw Error(scene.material.location(key),
                    std::string("section [material]: give preset or ") + key + ", not both");
    if (!table->get("eta")) scene.material.set("eta", 1.3);  // Jensen et al.'s measurements
  }
  scene.transport = read_section(root, "transport", transport_schema(), scene);
  scene.lighting = read_section(root, "lighting", lighting_schema(), scene, "point");
  scene.point_lights = read_point_lights(root["lighting"].as_table(), scene.file);
  scene.camera = read_section(root, "camera", camera_schema(), scene);
  scene.output = read_section(root, "output", output_schema(), scene);
  scene.ground_truth = read_section(root, "ground_truth", ground_truth_schema(), scene);
}

// Keys that are each valid but not together.
void check_combinations(const SceneSpec& scene) {
  const bool has_file = !scene.mesh.get_string("file").empty();
  const bool has_generated = !scene.mesh.get_string("generate").empty();
  if (has_file == has_generated)
    throw Error(scene.mesh.location(),
                "section [mesh]: give exactly one of \"file\" or \"generate\"");
  const bool has_map = !scene.lighting.get_string("environment").empty();
  if (has_map && scene.lighting.has("constant"))
    throw Error(scene.lighting.location(),
                "section [lighting]: give one of \"environment\" or \"constant\", not both");
  if (!has_map && !scene.lighting.has("constant") && scene.point_lights.empty())
    throw Error(scene.lighting.location(),
                "section [lighting]: give \"environment\", \"constant\" or [[lighting.point]] "
                "lights");
  const int bounces = static_cast<int>(scene.transport.get_int("bounces"));
  if (!scene.point_lights.empty() && bounces > 0)
    throw Error(scene.transport.location("bounces"),
                "section [transport]: point lights shade direct light only (the transfer's "
                "bounces assume distant light); use bounces = 0 with [[lighting.point]]");
  if (!scene.point_lights.empty() && scene.channels().groups.size() > 1)
    throw Error(scene.material.location(),
                "section [material]: point lights need one transfer for all colour channels; this "
                "material's channels differ (coloured diffuse/specular with glossy or bounces, or "
                "coloured subsurface): use grey coefficients with [[lighting.point]]");
  if (bounces > 0 && !scene.transport.get_bool("shadowed"))
    throw Error(scene.transport.location("bounces"),
                "section [transport]: bounces gather light from the shadow rays' hits; they need "
                "shadowed = true");
}

}  // namespace

SceneSpec SceneSpec::parse(const std::string& text, const fs::path& file,
                           const PluginRegistry& registry) {
  SceneSpec scene;
  scene.file = file;
  scene.text = text;
  const toml::table root = parse_toml(text, file);
  check_sections(root, file);
  read_sections(root, scene);
  check_combinations(scene);
  scene.basis = read_plugin(root, "basis", "sh", PluginKind::basis, registry, scene);
  // The exit basis serves glossy materials; a lambert one still has it
  // checked (a sweep may vary the BRDF over one scene file).
  if (scene.glossy() || root["exit"].as_table())
    scene.exit = read_plugin(root, "exit", "hsh", PluginKind::basis, registry, scene);
  scene.compressor =
      read_plugin(root, "compressor", "none", PluginKind::compressor, registry, scene);
  scene.renderer = read_plugin(root, "renderer", "cpu", PluginKind::renderer, registry, scene);
  return scene;
}

}  // namespace prt
