// prt compress BAKE --sweep 'vq clusters=64|pca components=4|cpca clusters=64 components=4':
// each configuration encodes the bake's stored exact transfer (no rays; the
// bake is not rewritten) in the bake's rendered metric, and the table ranks
// them by what a renderer must hold (floats and cluster indices) against
// the error relative to the signal's energy, with the Pareto front and a
// recommendation per budget.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "commands.hpp"
#include "plugin_spec.hpp"
#include "prt/bake_checks.hpp"
#include "prt/bake_file.hpp"
#include "prt/compressor.hpp"
#include "prt/output_file.hpp"
#include "prt/pipeline.hpp"
#include "prt/progress.hpp"

namespace prt::cli {

namespace {

struct Row {
  std::string label;
  CompressionReport report;
  bool front = false;
};

// Indices on the Pareto front of (total bytes, relative SE), by bytes.
void mark_front(std::vector<Row>& rows) {
  std::sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) {
    return a.report.total_bytes() != b.report.total_bytes()
               ? a.report.total_bytes() < b.report.total_bytes()
               : a.report.relative_squared_error() < b.report.relative_squared_error();
  });
  double best = INFINITY;
  for (Row& r : rows)
    if (r.report.relative_squared_error() < best)
      r.front = true, best = r.report.relative_squared_error();
}

void print_table(const std::vector<Row>& rows, double vertices) {
  std::printf("%-36s %10s %9s %12s %12s %9s %9s %6s\n", "configuration", "MB total", "B/vertex",
              "SE/energy", "p99 vertex", "encode s", "overdraw", "front");
  for (const Row& r : rows)
    std::printf("%-36s %10.3f %9.1f %12.4g %12.4g %9.2f %9.3f %6s\n", r.label.c_str(),
                r.report.total_bytes() / 1e6, r.report.total_bytes() / vertices,
                r.report.relative_squared_error(), r.report.vertex_error_p99,
                r.report.encode_seconds, r.report.overdraw, r.front ? "*" : "");
  std::printf(
      "MB total: the floats a renderer holds (4 bytes each) plus a 32-bit cluster id per vertex "
      "when there is more than one cluster; SE/energy: squared error over the signal's energy, "
      "in the bake's %s metric; *: on the Pareto front (no configuration is both smaller and "
      "more accurate)\n",
      rows.empty() || !rows[0].report.rendered_metric ? "coefficient" : "rendered");
}

// The best front configuration within each budget, then the knee.
void print_recommendation(const std::vector<Row>& rows, const std::vector<std::uint64_t>& budgets) {
  std::vector<const Row*> front;
  for (const Row& r : rows)
    if (r.front) front.push_back(&r);
  if (front.empty()) return;
  for (const std::uint64_t budget : budgets) {
    const Row* best = nullptr;
    for (const Row* r : front)
      if (r->report.total_bytes() <= double(budget)) best = r;  // front: later is more accurate
    if (best)
      std::printf("within %.3f MB: %s (%.3f MB, SE/energy %.4g)\n", double(budget) / 1e6,
                  best->label.c_str(), best->report.total_bytes() / 1e6,
                  best->report.relative_squared_error());
    else
      std::printf("within %.3f MB: nothing swept fits (the smallest is %s at %.3f MB)\n",
                  double(budget) / 1e6, front.front()->label.c_str(),
                  front.front()->report.total_bytes() / 1e6);
  }
  // The knee: the front step that buys the most error per byte (log-log slope).
  const Row* knee = front.front();
  double steepest = 0;
  for (std::size_t i = 1; i < front.size(); ++i) {
    const double bytes =
        std::log(front[i]->report.total_bytes() / front[i - 1]->report.total_bytes());
    const double error = std::log(front[i - 1]->report.relative_squared_error() /
                                  std::max(front[i]->report.relative_squared_error(), 1e-300));
    if (bytes > 0 && error / bytes > steepest) steepest = error / bytes, knee = front[i];
  }
  std::printf(
      "recommendation: %s is the smallest swept encoding; %s the most accurate; %s gains the "
      "most accuracy per byte along the front (the knee): below it each byte buys much, "
      "above it little\n",
      front.front()->label.c_str(), front.back()->label.c_str(), knee->label.c_str());
}

nlohmann::ordered_json rows_json(const std::vector<Row>& rows) {
  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  for (const Row& r : rows) {
    auto j = nlohmann::ordered_json::parse(r.report.json());
    j["configuration"] = r.label;
    j["pareto_front"] = r.front;
    out.push_back(std::move(j));
  }
  return out;
}

}  // namespace

int compress_sweep(Context& context, const CompressArgs& args) {
  if (!args.compressor.empty() || !args.parameters.empty() || !args.output.empty())
    throw Error(
        "--sweep: give the configurations there alone (\"cpca clusters=64|vq "
        "clusters=256\"); -c, -p and -o are for one re-compression");
  std::vector<PluginSpec> configurations;
  for (const std::string& sweep : args.sweeps) {
    std::stringstream list(sweep);
    for (std::string item; std::getline(list, item, '|');)
      configurations.push_back(parse_plugin_spec(item, ' ', "--sweep"));
  }
  const BakeData data = read_bake(args.bake);
  check_bake_records(args.bake, data, context.registry);
  // Every configuration checked before any encoding.
  std::vector<std::shared_ptr<Compressor>> compressors;
  for (PluginSpec& c : configurations) {
    compressors.push_back(
        context.registry.create<Compressor>(c.name, c.params, c.params.location()));
    refuse_budget_beyond_signal(c.params, data.transfer.dimension(), c.name);
  }
  const RenderedMetric metric = rendered_metric(data, context.registry);
  const Distribution whole = Distribution::whole_signal(data.transfer.vertices());
  std::vector<Row> rows;
  Progress progress("compress sweep", double(configurations.size()), "", context.quiet);
  for (std::size_t i = 0; i < configurations.size(); ++i) {
    Stopwatch clock;
    std::optional<TransferSignal> loaded;
    const CompressedTransfer encoded = encode_in_metric(
        *compressors[i],
        readable_signal(*compressors[i], configurations[i].name, data.transfer, loaded),
        &data.row_mesh(), whole, metric);
    rows.push_back({configurations[i].text, measure(data.transfer, encoded, &data.row_mesh(),
                                                    clock.seconds(), whole, &metric)});
    progress.add(1);
  }
  mark_front(rows);
  if (args.json) {
    std::cout << rows_json(rows).dump(2) << "\n";
    return 0;
  }
  std::printf("%s: %lld vertices x %lld coefficients, %zu configurations (the bake is unchanged)\n",
              args.bake.c_str(), static_cast<long long>(data.transfer.vertices()),
              static_cast<long long>(data.transfer.dimension()), rows.size());
  print_table(rows, double(data.transfer.vertices()));
  print_recommendation(rows, args.budgets);
  return 0;
}

}  // namespace prt::cli
