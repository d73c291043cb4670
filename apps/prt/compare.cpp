// prt compare-bases: one set of rays, several bases; per basis the L2 error of
// the reconstructed per-vertex transport functions and the RMS shading error
// against the ground truth under the scene's light.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>

#include "commands.hpp"
#include "prt/basis.hpp"
#include "prt/environment.hpp"
#include "prt/output_file.hpp"
#include "prt/pipeline.hpp"
#include "prt/progress.hpp"
#include "prt/transport.hpp"

namespace prt::cli {

namespace {

struct BasisSpec {
  std::string text, name;
  Params params;
};

// "haar:k=96:resolution=16" -> name and typed parameters.
BasisSpec parse_spec(const std::string& text) {
  BasisSpec spec{text, "", Params(SourceLocation{"--bases \"" + text + "\""})};
  std::stringstream parts(text);
  std::getline(parts, spec.name, ':');
  std::size_t index = 0;
  for (std::string item; std::getline(parts, item, ':');)
    parse_parameter(item, index++, spec.params);
  return spec;
}

struct Row {
  std::string spec;
  int coefficients = 0;
  double bytes = 0, transport_error = 0, shading_rms = 0, shading_relative = 0, seconds = 0;
};

}  // namespace

int compare_bases(Context& context, const CompareArgs& args) {
  const SceneSpec scene = SceneSpec::load(args.scene, context.registry);
  for (const std::string& table : {args.csv, args.json})
    if (!table.empty())
      check_output({table, FileKind::text, "table"}, scene.input_files(), args.force);
  const Mesh mesh = scene.load_mesh();
  const DirectionSet set = scene.directions();
  std::vector<BasisSpec> specs;
  std::stringstream list(args.bases);
  for (std::string item; std::getline(list, item, ',');) specs.push_back(parse_spec(item));
  // Validate every basis before any ray is cast; a lattice basis's resolution
  // follows the scene's cube map unless given.
  const int lattice =
      set.kind == "cubemap" ? static_cast<int>(std::lround(std::sqrt(set.size() / 6.0))) : 0;
  for (auto& spec : specs) {
    const auto& d = context.registry.find(PluginKind::basis, spec.name, spec.params.location());
    if (d.schema().find("resolution") && !spec.params.has("resolution")) {
      if (!lattice)
        throw Error(scene.transport.location("directions"),
                    "basis \"" + spec.name +
                        "\" lives on a cube map: set [transport] directions "
                        "= \"cubemap\" so one set of rays serves every basis");
      spec.params.set("resolution", std::int64_t(lattice));
    }
    spec.params.validate(d.schema());
  }

  TransportOptions options;
  options.shadowed = scene.transport.get_bool("shadowed");
  options.keep_visibility = true;
  TransportResult traced;
  {
    Progress progress("trace once", double(mesh.vertex_count()), "rays");
    traced = diffuse_transfer(mesh, set, Eigen::MatrixXd(set.size(), 0), options, &progress);
  }
  const Environment environment = scene.load_environment();
  Eigen::MatrixX3f truth;
  {
    Progress progress("ground truth", double(mesh.vertex_count()), "rays");
    truth = ground_truth_radiance(
        mesh, environment, static_cast<int>(scene.ground_truth.get_int("samples")),
        static_cast<std::uint64_t>(scene.ground_truth.get_int("seed")), &progress);
  }

  std::vector<Row> rows;
  for (auto& spec : specs) {
    Stopwatch clock;
    auto basis = context.registry.create<Basis>(spec.name, spec.params, spec.params.location());
    if (basis->domain() != Domain::sphere)
      throw Error(spec.params.location(), "basis \"" + spec.name + "\" is not a sphere basis");
    if (basis->can_fit()) basis->fit({&mesh, &set, &traced.visibility});
    const TransferSignal exact = project_visibility(mesh, set, traced.visibility, *basis);
    const int terms = basis->approximation_terms();
    Params none_params;
    const CompressedTransfer coded =
        terms > 0 ? keep_largest(exact, terms)
                  : context.registry.create<Compressor>("none", none_params)->encode(exact, &mesh);
    Row row;
    row.spec = spec.text;
    row.seconds = clock.seconds();
    row.coefficients = terms > 0 ? coded.components : basis->size();
    row.bytes = 4 * coded.stored_floats();

    // Transport error: sum_k w_k (T_pk - t^_pk)^2 over all vertices, relative.
    const Eigen::MatrixXd values = basis->evaluate(set.directions);  // s x n
    const MatrixXfRow decoded = coded.decode();
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
    row.transport_error = std::sqrt(error / std::max(energy, 1e-300));

    Eigen::MatrixX3f radiance = relight(coded, environment.project(*basis));
    const ErrorStats shading = vertex_error(radiance, truth);
    row.shading_rms = shading.rms;
    row.shading_relative = shading.relative_rms;
    rows.push_back(row);
    std::fprintf(stderr, "%s: %d coefficients, transport error %.4f, shading RMS %.5g\n",
                 spec.text.c_str(), row.coefficients, row.transport_error, row.shading_rms);
  }

  std::ostringstream csv, json;
  csv << "basis,coefficients,bytes,transport_l2_relative,shading_rms,shading_relative_rms,"
         "seconds\n";
  json << "[";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    char line[512];
    std::snprintf(line, sizeof line, "\"%s\",%d,%.0f,%.6g,%.6g,%.6g,%.3f\n", r.spec.c_str(),
                  r.coefficients, r.bytes, r.transport_error, r.shading_rms, r.shading_relative,
                  r.seconds);
    csv << line;
    std::snprintf(line, sizeof line,
                  "%s\n {\"basis\": \"%s\", \"coefficients\": %d, \"bytes\": %.0f, "
                  "\"transport_l2_relative\": %.6g, \"shading_rms\": %.6g, "
                  "\"shading_relative_rms\": %.6g, \"seconds\": %.3f}",
                  i ? "," : "", r.spec.c_str(), r.coefficients, r.bytes, r.transport_error,
                  r.shading_rms, r.shading_relative, r.seconds);
    json << line;
  }
  json << "\n]\n";
  if (!args.csv.empty()) write_text_file(args.csv, csv.str());
  if (!args.json.empty()) write_text_file(args.json, json.str());
  std::printf("%-28s %6s %12s %14s %12s %10s\n", "basis", "coeffs", "bytes", "transport L2",
              "shading RMS", "relative");
  for (const auto& r : rows)
    std::printf("%-28s %6d %12.0f %14.4f %12.5g %10.4f\n", r.spec.c_str(), r.coefficients, r.bytes,
                r.transport_error, r.shading_rms, r.shading_relative);
  return 0;
}

}  // namespace prt::cli
