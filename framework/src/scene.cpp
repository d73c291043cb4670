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
#include "prt/scene_keys.hpp"
#include "prt/sh.hpp"
#include "scene_ascii.hpp"
#include "toml_checked.hpp"

namespace prt {
namespace fs = std::filesystem;
using namespace prt::schema;

namespace {

const ParamSchema& mesh_schema() {
  static const ParamSchema s{"section [mesh]",
                             {keys::mesh::file, keys::mesh::generate, keys::mesh::detail}};
  return s;
}
ParamSchema place_schema(const char* owner) {
  return ParamSchema{owner,
                     {keys::place::file, keys::place::generate, keys::place::detail,
                      keys::place::position, keys::place::size}};
}
const ParamSchema& receivers_schema() {
  static const ParamSchema s{"section [receivers]",
                             {keys::receivers::kind, keys::receivers::resolution,
                              keys::receivers::spacing, keys::receivers::interpolation,
                              keys::receivers::normal_bias, keys::receivers::invalid_fraction}};
  return s;
}
const ParamSchema& material_schema() {
  static const ParamSchema s{
      "section [material]",
      {keys::material::albedo, keys::material::brdf, keys::material::diffuse,
       keys::material::specular, keys::material::exponent, keys::material::anisotropic_roughness,
       keys::material::roughness, keys::material::fresnel, keys::material::incident_order,
       keys::material::projection, keys::material::cutoff, keys::material::subsurface,
       keys::material::sigma_a, keys::material::sigma_s, keys::material::preset,
       keys::material::eta, keys::material::mm_per_unit, keys::material::subsurface_error}};
  return s;
}
const ParamSchema& transport_schema() {
  static const ParamSchema s{
      "section [transport]",
      {keys::transport::directions, keys::transport::rays, keys::transport::shadowed,
       keys::transport::bounces, keys::transport::seed}};
  return s;
}
const ParamSchema& lighting_schema() {
  static const ParamSchema s{
      "section [lighting]",
      {keys::lighting::environment, keys::lighting::constant, keys::lighting::intensity,
       keys::lighting::rotation, keys::lighting::window, keys::lighting::nearest}};
  return s;
}
const ParamSchema& point_light_schema() {
  static const ParamSchema s{
      "[[lighting.point]]",
      {keys::point::position, keys::point::colour, keys::point::intensity, keys::point::radius}};
  return s;
}
const ParamSchema& camera_schema() {
  static const ParamSchema s{
      "section [camera]",
      {keys::camera::position, keys::camera::target, keys::camera::up, keys::camera::fov,
       keys::camera::width, keys::camera::height, keys::camera::exposure}};
  return s;
}
const ParamSchema& output_schema() {
  static const ParamSchema s{"section [output]", {keys::output::bake, keys::output::image}};
  return s;
}
const ParamSchema& ground_truth_schema() {
  static const ParamSchema s{"section [ground_truth]",
                             {keys::ground_truth::samples, keys::ground_truth::seed}};
  return s;
}

const std::array<std::string, 13> kSections = {
    "mesh",     "material", "transport", "basis",        "exit",      "compressor", "lighting",
    "renderer", "camera",   "output",    "ground_truth", "receivers", "moving"};

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
    if (!keys::point::position.given(params))
      throw Error(where, "[[lighting.point]]: \"position\" is required");
    PointLight light;
    light.position = Eigen::Vector3d(keys::point::position(params).data());
    light.colour = Eigen::Vector3d(keys::point::colour(params).data());
    light.intensity = keys::point::intensity(params);
    light.radius = keys::point::radius(params);
    lights.push_back(light);
  }
  return lights;
}

// [[mesh.add]]: meshes placed in the scene, each validated like a section.
std::vector<Params> read_mesh_parts(const toml::table* mesh, const SceneSpec& scene) {
  std::vector<Params> parts;
  const toml::node* node = mesh ? mesh->get("add") : nullptr;
  if (!node) return parts;
  const toml::array* array = node->as_array();
  if (!array || !array->is_array_of_tables())
    throw Error(location_of(node->source(), scene.file),
                "section [mesh]: \"add\" must be an array of tables, written [[mesh.add]] with "
                "file = \"...\", position = [x, y, z] and size under it");
  for (const toml::node& item : *array) {
    const toml::table& table = *item.as_table();
    Params params = read_table(&table, location_of(table.source(), scene.file), scene.file);
    params.validate(place_schema("[[mesh.add]]"));
    parts.push_back(std::move(params));
  }
  return parts;
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
                            "]; valid: mesh, material, transport, basis, exit, compressor, "
                            "lighting, renderer, camera, output, ground_truth, receivers, moving";
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
  const SourceLocation where =
      table ? location_of(table->source(), scene.file) : SourceLocation{scene.file.string(), 1, 1};
  Params params = read_table(table, where, scene.file, skip);
  params.validate(schema);
  resolve_paths(params, schema, scene);
  return params;
}

void read_sections(const toml::table& root, SceneSpec& scene) {
  scene.mesh = read_section(root, "mesh", mesh_schema(), scene, "add");
  scene.mesh_parts = read_mesh_parts(root["mesh"].as_table(), scene);
  for (Params& part : scene.mesh_parts) resolve_paths(part, place_schema("[[mesh.add]]"), scene);
  scene.receivers = read_section(root, "receivers", receivers_schema(), scene);
  scene.moving = read_section(root, "moving", place_schema("section [moving]"), scene);
  scene.moving_given = root["moving"].as_table() != nullptr;
  scene.material = read_section(root, "material", material_schema(), scene);
  if (!keys::material::preset(scene.material).empty()) {  // measured coefficients replace the keys
    const toml::table* table = root["material"].as_table();
    for (const char* key : {keys::material::sigma_a.name(), keys::material::sigma_s.name()})
      if (table->get(key))
        throw Error(scene.material.location(key),
                    std::string("section [material]: give preset or ") + key + ", not both");
    if (!table->get(keys::material::eta.name()))  // Jensen et al.'s measurements
      scene.material.set(keys::material::eta.name(), 1.3);
  }
  scene.transport = read_section(root, "transport", transport_schema(), scene);
  scene.lighting = read_section(root, "lighting", lighting_schema(), scene, "point");
  scene.point_lights = read_point_lights(root["lighting"].as_table(), scene.file);
  scene.camera = read_section(root, "camera", camera_schema(), scene);
  scene.output = read_section(root, "output", output_schema(), scene);
  scene.ground_truth = read_section(root, "ground_truth", ground_truth_schema(), scene);
}

// A placed mesh names exactly one of a file or a generated mesh.
void check_placed(const Params& params, const char* where) {
  if (keys::place::file(params).empty() == keys::place::generate(params).empty())
    throw Error(params.location(),
                std::string(where) + ": give exactly one of \"file\" or \"generate\"");
}

// What probes receive: distant light over the sphere, shadowed by the scene
// (docs/receivers.md); what they do not yet, refused before any ray.
// What texels receive: distant light, shadowed by the mesh, at a diffuse
// surface; what they do not yet, refused before any ray.
void check_texels(const SceneSpec& scene) {
  const SourceLocation where = scene.receivers.location(keys::receivers::kind.name());
  auto refuse = [&](const std::string& what) {
    throw Error(where,
                "section [receivers]: texels receive distant light, shadowed by the "
                "mesh, at a diffuse surface; " +
                    what);
  };
  if (!scene.mesh_parts.empty())
    refuse(
        "[[mesh.add]] joins meshes without one atlas: join them in one file with texture "
        "coordinates");
  if (scene.glossy()) refuse("glossy transfer at texels is not built yet: use lambert");
  if (keys::transport::bounces(scene.transport) > 0)
    refuse("inter-reflected light at texels is not built yet: use bounces = 0");
  if (keys::material::subsurface(scene.material))
    refuse("subsurface light at texels is not built yet");
  if (!scene.point_lights.empty()) refuse("point lights at texels are not built yet");
}

void check_receivers(const SceneSpec& scene) {
  for (const Params& part : scene.mesh_parts) check_placed(part, "[[mesh.add]]");
  if (scene.texels()) check_texels(scene);
  if (!scene.probes()) {
    if (scene.has_moving())
      throw Error(scene.moving.location(),
                  "section [moving]: a moving object is shaded from probes; set [receivers] kind "
                  "= \"probes\"");
    return;
  }
  if (scene.has_moving()) check_placed(scene.moving, "section [moving]");
  const SourceLocation where = scene.receivers.location(keys::receivers::kind.name());
  auto refuse = [&](const std::string& what) {
    throw Error(where,
                "section [receivers]: probes receive distant light, shadowed by the "
                "scene; " +
                    what);
  };
  if (scene.glossy()) refuse("a glossy material is a surface's, not a probe's: use lambert");
  if (keys::transport::bounces(scene.transport) > 0)
    refuse("inter-reflected light at probes is not built yet: use bounces = 0");
  if (keys::material::subsurface(scene.material)) refuse("subsurface light needs a surface");
  if (!scene.point_lights.empty()) refuse("point lights at probes are not built yet");
  if (scene.channels().groups.size() > 1)
    refuse("one transfer serves every colour channel: use a grey diffuse");
}

// Keys that are each valid but not together.
void check_combinations(const SceneSpec& scene) {
  const bool has_file = !keys::mesh::file(scene.mesh).empty();
  const bool has_generated = !keys::mesh::generate(scene.mesh).empty();
  if (has_file == has_generated)
    throw Error(scene.mesh.location(),
                "section [mesh]: give exactly one of \"file\" or \"generate\"");
  const bool has_map = !keys::lighting::environment(scene.lighting).empty();
  if (has_map && scene.lighting.has(keys::lighting::constant.name()))
    throw Error(scene.lighting.location(),
                "section [lighting]: give one of \"environment\" or \"constant\", not both");
  if (!has_map && !scene.lighting.has(keys::lighting::constant.name()) &&
      scene.point_lights.empty())
    throw Error(scene.lighting.location(),
                "section [lighting]: give \"environment\", \"constant\" or [[lighting.point]] "
                "lights");
  const int bounces = static_cast<int>(keys::transport::bounces(scene.transport));
  if (!scene.point_lights.empty() && bounces > 0)
    throw Error(scene.transport.location(keys::transport::bounces.name()),
                "section [transport]: point lights shade direct light only (the transfer's "
                "bounces assume distant light); use bounces = 0 with [[lighting.point]]");
  if (!scene.point_lights.empty() && scene.channels().groups.size() > 1)
    throw Error(scene.material.location(),
                "section [material]: point lights need one transfer for all colour channels; this "
                "material's channels differ (coloured diffuse/specular with glossy or bounces, or "
                "coloured subsurface): use grey coefficients with [[lighting.point]]");
  check_receivers(scene);
  if (bounces > 0 && !keys::transport::shadowed(scene.transport))
    throw Error(scene.transport.location(keys::transport::bounces.name()),
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
    // At probes [exit] is the incident basis, a sphere basis: sh by default.
    scene.exit = read_plugin(root, "exit", scene.probes() ? "sh" : "hsh", PluginKind::basis,
                             registry, scene);
  scene.compressor =
      read_plugin(root, "compressor", "none", PluginKind::compressor, registry, scene);
  scene.renderer = read_plugin(root, "renderer", "cpu", PluginKind::renderer, registry, scene);
  return scene;
}

}  // namespace prt
