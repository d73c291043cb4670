// Checks that a bake file fits the scene and plug-ins that read it, and the
// bases a bake makes from its own plug-in records.
#include "prt/bake_checks.hpp"

#include <algorithm>
#include <sstream>

#include "prt/basis.hpp"
#include "prt/compressor.hpp"
#include "prt/log.hpp"
#include "prt/rendered_metric.hpp"

namespace prt {

namespace {

void check_plugin_matches(const PluginRecord& baked, const PluginChoice& wanted, const char* role) {
  const std::string parameters = wanted.params.describe();
  if (same_plugin(baked.name, baked.parameters, wanted.name, parameters)) return;
  auto first_line = [](const std::string& text) { return text.substr(0, text.find('\n')); };
  throw Error(wanted.where, std::string("the bake file was made with ") + role + " \"" +
                                baked.name + "\" (" + first_line(baked.parameters) +
                                "), but the scene asks for \"" + wanted.name + "\" (" +
                                first_line(parameters) + "); bake again");
}

}  // namespace

void check_bake_matches(const BakeData& data, const SceneSpec& scene) {
  const std::string material = scene.material_description();
  const int bounces = static_cast<int>(keys::transport::bounces(scene.transport));
  if (data.material != material || data.bounces != bounces ||
      data.subsurface != keys::material::subsurface(scene.material) ||
      data.transfer.glossy() != scene.glossy())
    throw Error(scene.material.location(),
                "the bake file was made for material \"" + data.material + "\" with " +
                    std::to_string(data.bounces) + " bounces" +
                    (data.subsurface ? " and subsurface" : "") + ", but the scene asks for \"" +
                    material + "\" with " + std::to_string(bounces) + " bounces; bake again");
  check_plugin_matches(data.basis, scene.basis, "basis");
  if (scene.glossy() || (scene.probes() && !scene.exit.name.empty()))
    check_plugin_matches(data.exit, scene.exit, "exit basis");
  if (data.receivers.kind != keys::receivers::kind(scene.receivers))
    throw Error(scene.receivers.location(), "the bake file holds transfer at " +
                                                data.receivers.kind + ", but the scene asks for " +
                                                keys::receivers::kind(scene.receivers) +
                                                "; bake again");
  const auto resolution = keys::receivers::resolution(scene.receivers);
  if (data.receivers.texels() && data.receivers.atlas.width != resolution)
    throw Error(scene.receivers.location(keys::receivers::resolution.name()),
                "the bake file holds texels of a " + std::to_string(data.receivers.atlas.width) +
                    " x " + std::to_string(data.receivers.atlas.height) +
                    " atlas, but the scene asks for resolution " + std::to_string(resolution) +
                    "; bake again");
}

void check_bake_dimension(const BakeData& data, const Basis& basis) {
  const Eigen::Index expected =
      Eigen::Index(basis.size()) * data.transfer.exit_rows * data.transfer.channel_groups;
  if (data.transfer.dimension() != expected)
    throw Error(data.scene_file + ": the bake's transfer has " +
                std::to_string(data.transfer.dimension()) + " columns, but basis \"" +
                data.basis.name + "\" has " + std::to_string(basis.size()) + " coefficients" +
                (data.transfer.glossy()
                     ? " x " + std::to_string(data.transfer.exit_rows) + " exit rows"
                     : std::string()) +
                (data.transfer.channel_groups > 1
                     ? " x " + std::to_string(data.transfer.channel_groups) + " channel transfers"
                     : std::string()) +
                "; the bake file does not match its plug-ins (bake again)");
}

namespace {

// A plug-in record's parameters ("key = value" lines, as Params::describe
// writes them), typed as the scene's would be.
Params params_of_record(const PluginRecord& record, const SourceLocation& where) {
  Params params(where);
  const auto trim = [](std::string text) {
    const auto first = text.find_first_not_of(" \t"), last = text.find_last_not_of(" \t");
    return first == std::string::npos ? std::string() : text.substr(first, last - first + 1);
  };
  std::istringstream lines(record.parameters);
  for (std::string line; std::getline(lines, line);) {
    const auto equals = line.find('=');
    if (trim(line).empty()) continue;
    if (equals == std::string::npos) throw Error(where, "unreadable parameter \"" + line + "\"");
    parse_assignment(trim(line.substr(0, equals)) + "=" + trim(line.substr(equals + 1)), where,
                     params);
  }
  return params;
}

// A bake's basis made again from its plug-in record and its saved state:
// what re-compressing a bake file needs, without its scene's mesh or map (a
// bake may travel alone).
std::shared_ptr<Basis> basis_of_record(const PluginRecord& record, const BasisState& state,
                                       PluginRegistry& registry, const std::string& role) {
  const SourceLocation where{"the bake's " + role + " \"" + record.name + "\""};
  Params params = params_of_record(record, where);
  auto basis = registry.create<Basis>(record.name, params, where);
  basis->load(state);
  return basis;
}

bool installed(const PluginRegistry& registry, PluginKind kind, const std::string& name) {
  const auto names = registry.names(kind);
  return std::find(names.begin(), names.end(), name) != names.end();
}

void check_exit_rows(const BakeData& data, const Basis& exit) {
  if (exit.size() != data.transfer.exit_rows)
    throw Error("the bake's transfer has " + std::to_string(data.transfer.exit_rows) +
                " exit rows, but its exit basis \"" + data.exit.name + "\" has " +
                std::to_string(exit.size()) + " functions");
}

void check_compressor_record(const BakeData& data, PluginRegistry& registry,
                             std::vector<std::string>& unchecked) {
  const CompressedTransfer& c = data.compressed;
  if (data.compressor.name == kExactRecord) {  // written by a bake that kept the transfer exact
    if (c.sparse() || c.components != 0 || c.clusters() != c.vertices())
      throw Error("the bake says its transfer is exact, but it is stored in " +
                  std::to_string(c.clusters()) + " clusters of " + std::to_string(c.components) +
                  " components");
    return;
  }
  if (!installed(registry, PluginKind::compressor, data.compressor.name)) {
    unchecked.push_back("compressor \"" + data.compressor.name + "\"");
    return;
  }
  const SourceLocation where{"the bake's compressor \"" + data.compressor.name + "\""};
  Params params = params_of_record(data.compressor, where);
  const auto compressor = registry.create<Compressor>(data.compressor.name, params, where);
  try {
    compressor->check_encoding(c);
  } catch (const Error& e) {
    throw Error(where, e.what());
  }
}

}  // namespace

std::vector<std::string> check_bake_records(const std::string& file, const BakeData& data,
                                            PluginRegistry& registry) {
  std::vector<std::string> unchecked;
  try {
    if (installed(registry, PluginKind::basis, data.basis.name))
      check_bake_dimension(data, *basis_of_record(data.basis, data.basis_state, registry, "basis"));
    else
      unchecked.push_back("basis \"" + data.basis.name + "\"");
    if (data.transfer.glossy() || data.receivers.probes()) {
      if (installed(registry, PluginKind::basis, data.exit.name))
        check_exit_rows(data, *basis_of_record(data.exit, data.exit_state, registry, "exit basis"));
      else
        unchecked.push_back("exit basis \"" + data.exit.name + "\"");
    }
    check_compressor_record(data, registry, unchecked);
  } catch (const Error& e) {
    throw Error(file + ": bad bake file: " + e.what());
  }
  return unchecked;
}

RenderedMetric rendered_metric(const BakeData& data, PluginRegistry& registry) {
  if (data.receivers.probes()) return {};  // as the bake: the incident coefficients as they are
  std::shared_ptr<Basis> basis;
  try {
    basis = basis_of_record(data.basis, data.basis_state, registry, "basis");
  } catch (const Error& e) {  // e.g. a basis written in Python, absent from this process
    log_warning(std::string(e.what()) +
                "; without the bake's basis its transfer is compressed in coefficient space");
    return {};
  }
  check_bake_dimension(data, *basis);
  if (!data.transfer.glossy()) return RenderedMetric(*basis, nullptr);
  const auto exit = basis_of_record(data.exit, data.exit_state, registry, "exit basis");
  check_exit_rows(data, *exit);
  return RenderedMetric(*basis, exit.get());
}

void check_encoding(const BakeData& data, const CompressedTransfer& transfer,
                    const std::string& what, bool finite) {
  transfer.validate(static_cast<Eigen::Index>(data.receiver_count()), finite);
  const Eigen::Index columns =
      data.transfer.dimension() > 0 ? data.transfer.dimension() : data.compressed.dimension;
  if (transfer.dimension != columns)
    throw Error(what + ": the encoding has " + std::to_string(transfer.dimension) +
                " coefficients per vertex; this bake's transfer has " + std::to_string(columns));
}

}  // namespace prt
