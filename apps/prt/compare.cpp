// prt compare-bases: one set of rays, several bases; per basis the L2 error of
// the reconstructed per-vertex transport functions (diffuse) and the RMS
// shading error against the ground truth under the scene's light, the same
// quantity `prt render --compare` prints. Sphere bases take the light-basis
// role; hemisphere bases the exit-basis role of a glossy scene.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>

#include "commands.hpp"
#include "plugin_spec.hpp"
#include "prt/basis.hpp"
#include "prt/environment.hpp"
#include "prt/output_file.hpp"
#include "prt/pipeline.hpp"
#include "prt/progress.hpp"
#include "prt/transport.hpp"
#include "reference_options.hpp"

namespace prt::cli {

namespace {

struct Row {
  std::string spec;
  int coefficients = 0;
  double bytes = 0, shading_rms = 0, shading_relative = 0, seconds = 0;
  double relight_seconds = 0;  // one relight of every vertex toward the camera (median of 3)
  double noise_floor = 0;      // the ground truth's standard error (per-vertex RMS)
  double transport_error = std::numeric_limits<double>::quiet_NaN();  // diffuse only
};

// Relative L2 error of the reconstructed transport functions (diffuse):
// sum_k w_k (T_pk - t^_pk)^2 over all vertices and directions.
double transport_error(const Mesh& mesh, const DirectionSet& set, const TransportResult& traced,
                       const BakeData& data, const Basis& basis) {
  const Eigen::MatrixXd values = basis.evaluate(set.directions);  // s x n
  const MatrixXfRow decoded = data.compressed.decode();
  double error = 0, energy = 0;
  std::mutex lock;
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, mesh.vertex_count(), 256), [&](const auto& range) {
        Eigen::MatrixXd t;
        transport_rows(mesh, set, traced.visibility, range.begin(), range.end(), t);
        const Eigen::MatrixXd approx =
            decoded.middleRows(range.begin(), range.size()).template cast<double>() *
            values.transpose();
        const double e =
            ((t - approx).array().square().rowwise() * set.weights.transpose().array()).sum();
        const double n = (t.array().square().rowwise() * set.weights.transpose().array()).sum();
        std::lock_guard guard(lock);
        error += e;
        energy += n;
      });
  return std::sqrt(error / std::max(energy, 1e-300));
}

// A diffuse entry's transport error in `format`; `absent` for a glossy one.
std::string transport_text(double error, const char* format, const char* absent) {
  if (!std::isfinite(error)) return absent;
  char text[32];
  std::snprintf(text, sizeof text, format, error);
  return text;
}

// The scene with one --bases entry in the role its domain serves: a sphere
// basis replaces [basis] (the light basis); a hemisphere basis replaces [exit]
// (the exit basis of glossy transfer). Everything is validated here, before
// any ray: the entry's parameters, its domain, and the bake plan it makes.
struct Entry {
  PluginSpec spec;
  SceneSpec scene;
  BakePlan plan;
  bool exit_role = false;
};

Entry entry_for(const SceneSpec& scene, PluginSpec spec, const DirectionSet& set,
                PluginRegistry& registry) {
  bool exit_role = false;
  const SourceLocation where = spec.params.location();
  const auto& d = registry.find(PluginKind::basis, spec.name, where);
  // A lattice basis's resolution follows the scene's cube map unless given.
  if (d.schema().find("resolution") && !spec.params.has("resolution")) {
    if (set.kind != "cubemap")
      throw Error(where, "basis \"" + spec.name +
                             "\" lives on a cube map: set [transport] directions = \"cubemap\" so "
                             "one set of rays serves every basis");
    spec.params.set("resolution", std::int64_t(std::lround(std::sqrt(double(set.size()) / 6.0))));
  }
  spec.params.validate(d.schema());
  Params probe_params = spec.params;
  const auto probe = registry.create<Basis>(spec.name, probe_params, where);
  SceneSpec out = scene;
  PluginChoice choice{spec.name, where, spec.params};
  exit_role = probe->domain() != Domain::sphere;
  if (!exit_role) {
    out.basis = choice;
  } else if (scene.glossy()) {
    out.exit = choice;
  } else {
    throw Error(where, "basis \"" + spec.name +
                           "\" is a hemisphere basis: it serves as the exit basis of glossy "
                           "transfer, and this scene's material is lambert (compare it under a "
                           "glossy [material] brdf, or list sphere bases)");
  }
  try {
    BakePlan plan = plan_bake(out, registry);
    return {std::move(spec), std::move(out), std::move(plan), exit_role};
  } catch (const Error& e) {  // already located: name the entry in front
    throw Error(where.file + ": " + e.what());
  }
}

// What the scene's single trace, light, camera and truth give every entry.
struct Shared {
  const DirectionSet& set;
  const TransportResult& traced;
  const Mesh& mesh;
  const Environment& environment;
  const Camera& camera;
  const Reference& truth;
};

// One entry baked over the shared rays (its basis alone: its own sparse
// approximation, if any), relit and measured.
Row measure(Context& context, const Entry& entry, const Shared& shared) {
  Stopwatch clock;
  RunOptions reuse{true};
  reuse.traced = &shared.traced;
  reuse.compress = false;
  StageTimes times;
  const BakeData data = bake(entry.scene, entry.plan, reuse, times);
  const Relighting relighting(entry.scene, data, context.registry);
  Row row;
  row.spec = entry.spec.text;
  row.seconds = clock.seconds();
  // The entry's own size: the exit basis's rows, or the light basis's
  // coefficients (kept terms of a sparse approximation).
  row.coefficients = entry.exit_role            ? data.transfer.exit_rows
                     : data.compressed.sparse() ? data.compressed.components
                                                : relighting.basis().size();
  row.bytes = 4 * data.compressed.stored_floats();
  if (!data.transfer.glossy() && data.transfer.channel_groups == 1)  // one transport per vertex
    row.transport_error =
        transport_error(shared.mesh, shared.set, shared.traced, data, relighting.basis());
  const Eigen::MatrixX3d light = relighting.light(shared.environment);
  Eigen::MatrixX3f radiance;
  row.relight_seconds = median_seconds(3, [&] {
    radiance = relighting.relight(data.compressed, light, shared.camera).vertex_radiance;
  });
  const ErrorStats shading = vertex_error(radiance, shared.truth.radiance);
  row.shading_rms = shading.rms;
  row.shading_relative = shading.relative_rms;
  row.noise_floor = shared.truth.noise_floor();
  std::fprintf(stderr, "%s: %d %s, transport error %s, shading RMS %.5g (%s)\n", row.spec.c_str(),
               row.coefficients, entry.exit_role ? "exit functions" : "coefficients",
               transport_text(row.transport_error, "%.4f", "- (glossy)").c_str(), row.shading_rms,
               noise_note(row.shading_rms, row.noise_floor).c_str());
  return row;
}

// The table as CSV and JSON (when asked) and on standard output.
void write_tables(const std::vector<Row>& rows, const CompareArgs& args) {
  std::ostringstream csv;
  nlohmann::ordered_json json = nlohmann::ordered_json::array();
  csv << "basis,coefficients,bytes,transport_l2_relative,shading_rms,shading_relative_rms,"
         "noise_floor,resolved,seconds,relight_seconds\n";
  for (const Row& r : rows) {
    const bool has_transport = std::isfinite(r.transport_error);
    char line[512];
    const bool is_resolved = resolved(r.shading_rms, r.noise_floor);
    std::snprintf(line, sizeof line, "%s,%d,%.0f,%s,%.6g,%.6g,%.6g,%s,%.3f,%.5f\n",
                  nlohmann::json(r.spec).dump().c_str(), r.coefficients, r.bytes,
                  transport_text(r.transport_error, "%.6g", "").c_str(), r.shading_rms,
                  r.shading_relative, r.noise_floor, is_resolved ? "true" : "false", r.seconds,
                  r.relight_seconds);
    csv << line;
    json.push_back({{"basis", r.spec},
                    {"coefficients", r.coefficients},
                    {"bytes", r.bytes},
                    {"transport_l2_relative",
                     has_transport ? nlohmann::ordered_json(r.transport_error) : nullptr},
                    {"shading_rms", r.shading_rms},
                    {"shading_relative_rms", r.shading_relative},
                    {"noise_floor", r.noise_floor},
                    {"resolved", resolved(r.shading_rms, r.noise_floor)},
                    {"seconds", r.seconds},
                    {"relight_seconds", r.relight_seconds}});
  }
  if (!args.csv.empty()) write_text_file(args.csv, csv.str());
  if (!args.json.empty()) write_text_file(args.json, json.dump(2) + "\n");
  std::printf("%-28s %6s %12s %14s %12s %10s %11s %8s %11s\n", "basis", "coeffs", "bytes",
              "transport L2", "shading RMS", "relative", "noise floor", "bake s", "relight ms");
  for (const auto& r : rows)
    std::printf("%-28s %6d %12.0f %14s %12.5g %10.4f %11.4g %8.2f %11.2f%s\n", r.spec.c_str(),
                r.coefficients, r.bytes, transport_text(r.transport_error, "%.4f", "-").c_str(),
                r.shading_rms, r.shading_relative, r.noise_floor, r.seconds,
                1e3 * r.relight_seconds,
                resolved(r.shading_rms, r.noise_floor) ? "" : "  (not resolved: raise --samples)");
}

}  // namespace

int compare_bases(Context& context, const CompareArgs& args) {
  SceneSpec scene = SceneSpec::load(args.scene, context.registry);
  if (scene.probes() || scene.texels())  // it compares transfer at vertices
    throw Error(scene.receivers.location(keys::receivers::kind.name()),
                "prt compare-bases compares transfer at vertices; for " +
                    keys::receivers::kind(scene.receivers) + ", `prt " +
                    keys::receivers::kind(scene.receivers) +
                    "` measures a scene baked with each basis (docs/receivers.md)");
  apply_samples(args.reference, scene);
  if (!args.csv.empty())
    check_output({args.csv, report_kind(args.csv), "table"}, scene.input_files(), args.force);
  if (!args.json.empty())
    check_output({args.json, FileKind::json, "table"}, scene.input_files(), args.force);
  const DirectionSet set = scene.directions();
  std::vector<Entry> entries;  // every entry planned before any ray
  std::stringstream list(args.bases);
  for (std::string item; std::getline(list, item, ',');)
    entries.push_back(
        entry_for(scene, parse_plugin_spec(item, ':', "--bases"), set, context.registry));

  const TransportResult traced = trace_scene(scene, {context.quiet});
  const Mesh mesh = scene.load_mesh();
  const Environment environment = scene.load_environment();
  const Camera camera = scene.make_camera(mesh);
  // The same truth and the same relighting as `prt render --compare`.
  const Reference truth = reference_radiance(scene, mesh, environment, camera, {context.quiet},
                                             reference_cache(args.reference).get());
  std::fprintf(stderr, "%s\n", reference_summary(truth).c_str());
  const Shared shared{set, traced, mesh, environment, camera, truth};
  std::vector<Row> rows;
  for (const Entry& entry : entries) rows.push_back(measure(context, entry, shared));
  write_tables(rows, args);
  return 0;
}

}  // namespace prt::cli
