// What a scene makes once read: its files resolved, its mesh, directions,
// environment and camera, and its material as the stages need it (BRDF,
// channels, subsurface, albedo).
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
#include "prt/mesh_atlas.hpp"
#include "prt/mesh_compose.hpp"
#include "prt/plugin.hpp"
#include "prt/registry.hpp"
#include "prt/scene.hpp"
#include "prt/sh.hpp"

namespace prt {
namespace fs = std::filesystem;

fs::path SceneSpec::resolve(const std::string& relative) const {
  const fs::path p(relative);
  return p.is_absolute() ? p : (file.parent_path() / p).lexically_normal();
}

fs::path SceneSpec::bake_path() const {
  const std::string name = keys::output::bake(output);
  return name.empty() ? fs::path(file.stem().string() + ".h5") : resolve(name);
}

fs::path SceneSpec::image_path() const {
  const std::string name = keys::output::image(output);
  return name.empty() ? fs::path(file.stem().string() + ".png") : resolve(name);
}

std::vector<fs::path> SceneSpec::input_files() const {
  std::vector<fs::path> files{file};
  for (const std::string& name : {keys::mesh::file(mesh), keys::lighting::environment(lighting)})
    if (!name.empty()) files.emplace_back(name);
  for (const Params& part : mesh_parts)
    if (const std::string name = keys::place::file(part); !name.empty()) files.emplace_back(name);
  if (has_moving())
    if (const std::string name = keys::place::file(moving); !name.empty()) files.emplace_back(name);
  return files;
}

namespace {

// A [[mesh.add]] or [moving] mesh, placed.
Mesh load_placed(const Params& params, const Eigen::Vector3f& position) {
  try {  // its problems located at its table
    const std::string file_name = keys::place::file(params);
    const Mesh mesh = !file_name.empty() ? prt::load_mesh(file_name)
                                         : make_generated(keys::place::generate(params),
                                                          int(keys::place::detail(params)));
    return placed(mesh, position, float(keys::place::size(params)));
  } catch (const Error& e) {
    throw Error(params.location(), e.what());
  }
}

Eigen::Vector3f position_of(const Params& params) {
  return Eigen::Vector3d(keys::place::position(params).data()).cast<float>();
}

}  // namespace

Mesh SceneSpec::load_mesh() const {
  const std::string file_name = keys::mesh::file(mesh);
  Mesh loaded = !file_name.empty() ? prt::load_mesh(file_name, texels())
                                   : make_generated(keys::mesh::generate(mesh),
                                                    static_cast<int>(keys::mesh::detail(mesh)));
  for (const Params& part : mesh_parts) append(loaded, load_placed(part, position_of(part)));
  // Texels need an atlas: the file's, else CGAL's as-rigid-as-possible map of a disk.
  if (texels() && loaded.uvs.empty())
    compute_atlas(loaded, file_name.empty()
                              ? "generated mesh \"" + keys::mesh::generate(mesh) + "\""
                              : file_name);
  return loaded;
}

bool SceneSpec::probes() const {
  return keys::receivers::kind(receivers) == "probes";
}

bool SceneSpec::texels() const {
  return keys::receivers::kind(receivers) == "texels";
}

bool SceneSpec::has_moving() const {
  return moving_given;
}

Mesh SceneSpec::load_moving() const {
  return load_moving(position_of(moving));
}

Mesh SceneSpec::load_moving(const Eigen::Vector3f& position) const {
  if (!has_moving()) throw Error(file.string() + ": the scene has no [moving] object");
  return load_placed(moving, position);
}

DirectionSet SceneSpec::directions() const {
  return DirectionSet::make(keys::transport::directions(transport),
                            static_cast<int>(keys::transport::rays(transport)),
                            static_cast<std::uint64_t>(keys::transport::seed(transport)));
}

Environment SceneSpec::load_environment() const {
  const std::string map = keys::lighting::environment(lighting);
  // Point lights alone: a black environment.
  const Eigen::Vector3f constant =
      lighting.has(keys::lighting::constant.name())
          ? Eigen::Vector3f(
                Eigen::Vector3d(keys::lighting::constant(lighting).data()).cast<float>())
          : Eigen::Vector3f::Zero();
  Environment environment = map.empty() ? Environment::constant(constant) : Environment::load(map);
  environment.set_intensity(static_cast<float>(keys::lighting::intensity(lighting)));
  environment.set_rotation(rotation_about_up(keys::lighting::rotation(lighting)));
  return environment;
}

Eigen::MatrixX3d SceneSpec::project_light(const Environment& environment,
                                          const Basis& basis) const {
  // A basis on a lattice rotates the light by rotating the lattice (as the
  // viewer does, frame after frame); any other projects the map.
  const std::optional<LatticeRotation> lattice = LatticeRotation::of(basis, environment);
  Eigen::MatrixX3d light =
      lattice ? lattice->light(environment.rotation()) : environment.project(basis);
  const std::string kind = keys::lighting::window(lighting);
  if (kind == "none") return light;
  check_window(basis);
  const std::vector<int> bands = basis.coefficient_bands();
  const int order = *std::max_element(bands.begin(), bands.end()) + 1;
  const Eigen::VectorXd per_band = sh::window(order, kind);  // indexed l^2 + l + m: take m = -l
  for (std::size_t i = 0; i < bands.size(); ++i)
    light.row(Eigen::Index(i)) *= per_band[bands[i] * bands[i]];
  return light;
}

Camera SceneSpec::make_camera(const Mesh& m) const {
  Camera c = Camera::framing(m, static_cast<int>(keys::camera::width(camera)),
                             static_cast<int>(keys::camera::height(camera)),
                             static_cast<float>(keys::camera::fov(camera)));
  auto vec = [&](const char* key) {
    const auto v = camera.get_reals(key);
    return Eigen::Vector3f(float(v[0]), float(v[1]), float(v[2]));
  };
  if (camera.has(keys::camera::target.name())) c.target = vec("target");
  if (camera.has(keys::camera::position.name())) c.position = vec("position");
  c.up = vec("up");
  // A camera at its target, or looking along its up vector, sees nothing.
  const Eigen::Vector3f forward = c.target - c.position;
  const float scale = std::max({c.target.norm(), c.position.norm(), 1e-20f});
  if (!forward.allFinite() || forward.norm() <= 1e-6f * scale)
    throw Error(camera.has(keys::camera::position.name())
                    ? camera.location(keys::camera::position.name())
                    : camera.location(),
                "section [camera]: position and target coincide; the camera has no direction");
  if (c.up.norm() == 0 || forward.normalized().cross(c.up.normalized()).norm() < 1e-6f)
    throw Error(camera.has(keys::camera::up.name()) ? camera.location(keys::camera::up.name())
                                                    : camera.location(),
                "section [camera]: up is parallel to the viewing direction (or zero)");
  return c;
}

Brdf SceneSpec::brdf(int channel) const {
  Brdf b;
  b.model = brdf_model(keys::material::brdf(material));
  b.kd = keys::material::diffuse(material)[std::size_t(channel)];
  b.ks = b.glossy() ? keys::material::specular(material)[std::size_t(channel)] : 0.0;
  b.exponent = keys::material::exponent(material);
  const auto ward = keys::material::anisotropic_roughness(material);
  b.alpha_x = ward[0];
  b.alpha_y = ward[1];
  b.roughness = keys::material::roughness(material);
  b.f0 = keys::material::fresnel(material);
  return b;
}

bool SceneSpec::glossy() const {
  return brdf().glossy();
}

void SceneSpec::check_window(const Basis& light_basis) const {
  // The window damps each frequency band; a basis without bands cannot be windowed.
  if (keys::lighting::window(lighting) == "none") return;
  const std::vector<int> bands = light_basis.coefficient_bands();
  if (bands.size() != static_cast<std::size_t>(light_basis.size()) || bands.empty())
    throw Error(lighting.location(keys::lighting::window.name()),
                "section [lighting]: window damps frequency bands, and basis \"" + basis.name +
                    "\" has none (it declares no coefficient_bands()); use window = \"none\"");
}

int SceneSpec::incident_order(const Basis& light_basis) const {
  if (const auto order = keys::material::incident_order(material); order > 0) return int(order);
  const std::vector<int> bands = light_basis.coefficient_bands();
  if (bands.empty()) return 8;
  return std::clamp(*std::max_element(bands.begin(), bands.end()) + 1, 1, kMaxIncidentOrder);
}

double SceneSpec::bounce_albedo(int channel) const {
  const double kd = glossy() ? 1.0 : keys::material::diffuse(material)[std::size_t(channel)];
  const auto a = keys::material::albedo(material);
  return kd * (a[0] + a[1] + a[2]) / 3.0;
}

std::string SceneSpec::material_description() const {
  std::string text = brdf().describe();
  if (glossy())
    text += " projection=" + keys::material::projection(material) +
            " cutoff=" + std::to_string(keys::material::cutoff(material)) +
            " incident_order=" + std::to_string(keys::material::incident_order(material));
  if (keys::material::subsurface(material)) {
    const SubsurfaceMaterial m = subsurface();
    char more[200];
    std::snprintf(more, sizeof more,
                  " subsurface sigma_a=%g sigma_s=%g eta=%g mm_per_unit=%g error=%g", m.sigma_a,
                  m.sigma_s, m.eta, m.mm_per_unit, m.error);
    text += more;
  }
  const MaterialChannels c = channels();
  if (c.groups.size() > 1) {  // the other channels' materials
    for (int channel = 1; channel < 3; ++channel) {
      const ChannelMaterial& g = c.groups[std::size_t(c.group_of_channel[channel])];
      char more[200];
      std::snprintf(more, sizeof more, " | %c: kd=%g ks=%g sigma_a=%g sigma_s=%g", "rgb"[channel],
                    g.brdf.kd, g.brdf.ks, g.subsurface.sigma_a, g.subsurface.sigma_s);
      text += more;
    }
  }
  return text;
}

MaterialChannels SceneSpec::channels() const {
  MaterialChannels out;
  const bool subsurface_on = keys::material::subsurface(material);
  const bool bounces = keys::transport::bounces(transport) > 0;
  // What a channel's transfer depends on; equal keys share a transfer.
  auto key = [&](int c) {
    const Brdf b = brdf(c);
    const SubsurfaceMaterial m = subsurface(c);
    const bool brdf_in_transfer = b.glossy() || bounces;
    return std::array<double, 4>{brdf_in_transfer ? b.kd : 0, brdf_in_transfer ? b.ks : 0,
                                 subsurface_on ? m.sigma_a : 0, subsurface_on ? m.sigma_s : 0};
  };
  std::vector<std::array<double, 4>> keys;
  for (int c = 0; c < 3; ++c) {
    const auto k = key(c);
    const auto found = std::find(keys.begin(), keys.end(), k);
    if (found != keys.end()) {
      out.group_of_channel[std::size_t(c)] = static_cast<int>(found - keys.begin());
      continue;
    }
    out.group_of_channel[std::size_t(c)] = static_cast<int>(keys.size());
    keys.push_back(k);
    out.groups.push_back({brdf(c), subsurface(c), bounce_albedo(c)});
  }
  return out;
}

SubsurfaceMaterial SceneSpec::subsurface(int channel) const {
  SubsurfaceMaterial m;
  const auto c = std::size_t(channel);
  if (const SubsurfacePreset* preset = subsurface_preset(keys::material::preset(material))) {
    m.sigma_a = preset->sigma_a[c];
    m.sigma_s = preset->sigma_s[c];
  } else {
    m.sigma_a = keys::material::sigma_a(material)[c];
    m.sigma_s = keys::material::sigma_s(material)[c];
  }
  m.eta = keys::material::eta(material);
  m.mm_per_unit = keys::material::mm_per_unit(material);
  m.error = keys::material::subsurface_error(material);
  return m;
}

Eigen::Vector3f SceneSpec::albedo() const {
  const auto a = keys::material::albedo(material);
  // A Lambertian transfer vector carries no reflectance: kd scales the tint.
  // A glossy matrix carries the whole BRDF, kd included.
  const Eigen::Vector3f tint = Eigen::Vector3d(a[0], a[1], a[2]).cast<float>();
  if (glossy()) return tint;
  const auto kd = keys::material::diffuse(material);
  return tint.cwiseProduct(Eigen::Vector3f(float(kd[0]), float(kd[1]), float(kd[2])));
}

}  // namespace prt
