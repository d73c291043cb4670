// prt bench: the speed/accuracy trade of a scene over a cartesian product of
// parameter values. Work that does not depend on a swept key is reused: rays
// are traced once per mesh/transport setting, transfer projected once per
// basis/material setting, the ground truth computed once per light. Results
// are appended to <out>/results.jsonl as each configuration finishes, so an
// interrupted sweep resumes where it stopped; CSV, JSON and the report
// (scripts/bench_report.py: plots, Pareto fronts, image strip) follow.
#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <numeric>
#include <set>
#include <sstream>
#include <type_traits>
#include <variant>

#include "commands.hpp"
#include "prt/bake_file.hpp"
#include "prt/basis.hpp"
#include "prt/compressor.hpp"
#include "prt/environment.hpp"
#include "prt/error.hpp"
#include "prt/glossy.hpp"
#include "prt/output_file.hpp"
#include "prt/pipeline.hpp"
#include "prt/progress.hpp"
#include "prt/scene.hpp"
#include "prt/transport.hpp"
#include "prt/turning_light.hpp"
#include "reference_options.hpp"

namespace prt::cli {

namespace fs = std::filesystem;

namespace {

struct Override {
  std::string section, key, value;
};

// "section.key=v1,v2,..." -> one list of overrides per swept key, or
// "section=plugin k=v k=v|plugin k=v" to swap a whole plug-in table (its
// parameters differ from plug-in to plug-in).
std::vector<Override> parse_sweep(const std::string& text) {
  const auto equals = text.find('='), dot = text.find('.');
  if (equals != std::string::npos && (dot == std::string::npos || dot > equals)) {
    std::vector<Override> values;
    std::stringstream list(text.substr(equals + 1));
    for (std::string v; std::getline(list, v, '|');)
      values.push_back({text.substr(0, equals), "", v});
    return values;
  }
  if (equals == std::string::npos || dot == std::string::npos || dot > equals)
    throw Error("--sweep \"" + text + "\": expected section.key=v1,v2,...");
  std::vector<Override> values;
  std::stringstream list(text.substr(equals + 1));
  for (std::string v; std::getline(list, v, ',');)
    values.push_back({text.substr(0, dot), text.substr(dot + 1, equals - dot - 1), v});
  if (values.empty()) throw Error("--sweep \"" + text + "\": no values");
  return values;
}

// A value typed as the scene parser types it (prt::parse_value).
void assign(toml::table& table, const std::string& key, const std::string& value) {
  std::visit(
      [&](const auto& typed) {
        using T = std::decay_t<decltype(typed)>;
        if constexpr (std::is_same_v<T, std::vector<double>>) {
          toml::array list;
          for (double x : typed) list.push_back(x);
          table.insert_or_assign(key, std::move(list));
        } else {
          table.insert_or_assign(key, typed);
        }
      },
      parse_value(value));
}

std::string scene_with(const std::string& text, const std::string& file,
                       const std::vector<Override>& overrides) {
  toml::table root = toml::parse(text, file);
  for (const Override& o : overrides) {
    if (o.key.empty()) {  // a whole plug-in table: "plugin k=v k=v"
      toml::table table;
      std::stringstream words(o.value);
      std::string word;
      words >> word;
      table.insert("plugin", word);
      while (words >> word) {
        const auto eq = word.find('=');
        if (eq == std::string::npos)
          throw Error("--sweep " + o.section + ": expected k=v, got " + word);
        assign(table, word.substr(0, eq), word.substr(eq + 1));
      }
      root.insert_or_assign(o.section, std::move(table));
      continue;
    }
    if (!root.contains(o.section)) root.insert(o.section, toml::table{});
    assign(*root[o.section].as_table(), o.key, o.value);
  }
  std::ostringstream out;
  out << root;
  return out.str();
}

// The overrides of the listed sections, as a cache key.
std::string key_of(const std::vector<Override>& overrides, const std::set<std::string>& sections,
                   bool exclude = false) {
  std::string key;
  for (const Override& o : overrides)
    if (sections.count(o.section) != exclude) key += o.section + "." + o.key + "=" + o.value + ";";
  return key;
}

std::string label_of(const std::vector<Override>& overrides) {
  std::string label;
  for (const Override& o : overrides)
    label += (label.empty() ? "" : " ") + (o.key.empty() ? o.value : o.key + "=" + o.value);
  return label.empty() ? "scene" : label;
}

// A file-name stem for a configuration's images.
std::string stem_of(const std::string& label) {
  std::string stem;
  for (char c : label) stem += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return stem;
}

// The JSON lines as CSV: the keys of the first line are the columns.
// One CSV row per JSON record, columns in the records' key order (strings
// quoted as JSON quotes them, which CSV readers accept).
void write_csv(const std::vector<nlohmann::ordered_json>& records, const fs::path& file) {
  std::string csv;
  for (std::size_t r = 0; r < records.size(); ++r) {
    std::string header, row;
    for (const auto& [key, value] : records[r].items()) {
      header += (header.empty() ? "" : ",") + key;
      row += (row.empty() ? "" : ",") + value.dump();
    }
    if (r == 0) csv += header + "\n";
    csv += row + "\n";
  }
  write_text_file(file, csv);
}

}  // namespace

double median_seconds(int runs, const std::function<void()>& work) {
  std::vector<double> t;
  for (int r = 0; r < runs; ++r) {
    Stopwatch clock;
    work();
    t.push_back(clock.seconds());
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

namespace {

// The cartesian product of the swept values.
std::vector<std::vector<Override>> configurations(const std::vector<std::string>& sweeps) {
  std::vector<std::vector<Override>> configs{{}};
  for (const std::string& sweep : sweeps) {
    std::vector<std::vector<Override>> next;
    for (const auto& config : configs)
      for (const Override& value : parse_sweep(sweep)) {
        next.push_back(config);
        next.back().push_back(value);
      }
    configs = std::move(next);
  }
  return configs;
}

// Configurations already in results.jsonl (a line cut by a kill is not a
// finished configuration: it runs again).
std::set<std::string> finished_labels(const fs::path& results) {
  std::set<std::string> done;
  if (std::ifstream in(results); in)
    for (std::string line; std::getline(in, line);) {
      const auto record = nlohmann::json::parse(line, nullptr, false);
      if (record.is_object() && record.contains("label") && record["label"].is_string())
        done.insert(record["label"].get<std::string>());
    }
  return done;
}

// Work shared by configurations that differ only in keys it does not read.
struct Reused {
  std::map<std::string, TransportResult> traces;
  std::map<std::string, std::pair<BakeData, double>> projections;  // transfer, seconds
  std::map<std::string, std::vector<Reference>> truths;
  // Ground truth under each light's band-limited reconstruction, per light
  // basis setting: the error budget's middle term.
  std::map<std::string, std::vector<Reference>> limited_truths;
  std::unique_ptr<const ReferenceCache> cache;  // references kept on disk between runs
};

// One configuration's bake: rays and projection reused, compression its own.
struct Baked {
  BakeData data;
  double trace_seconds = 0, project_seconds = 0, encode_seconds = 0;
  double se = 0, bytes = 0, file_bytes = 0;
};

Baked bake_configuration(const SceneSpec& scene, const BakePlan& plan,
                         const std::vector<Override>& config, Reused& reused, const fs::path& out) {
  static const std::set<std::string> trace_sections{"mesh", "transport"};
  static const std::set<std::string> shading_sections{"compressor", "camera",   "renderer",
                                                      "output",     "lighting", "ground_truth"};
  Baked baked;
  // 1. Rays, once per mesh and transport setting.
  const std::string trace_key = key_of(config, trace_sections);
  if (!reused.traces.count(trace_key))
    reused.traces.emplace(trace_key, trace_scene(scene, RunOptions{true}));
  const TransportResult& traced = reused.traces.at(trace_key);
  baked.trace_seconds = traced.trace_seconds;
  // 2. Projection (basis, material, bounces), once per such setting: a bake
  //    with the exact compressor over the stored visibility.
  const std::string projection_key = key_of(config, shading_sections, true);
  if (!reused.projections.count(projection_key)) {
    RunOptions reuse{true, &traced};
    reuse.compress = false;
    StageTimes times;
    Stopwatch clock;
    BakeData data = bake(scene, plan, reuse, times);
    reused.projections.emplace(projection_key, std::pair{std::move(data), clock.seconds()});
  }
  const auto& [exact_data, project_seconds] = reused.projections.at(projection_key);
  baked.project_seconds = project_seconds;
  // 3. Compression.
  baked.data = exact_data;
  BakeData& data = baked.data;
  Stopwatch clock;
  // An exact compressor keeps the bake's form (sparse for bases that approximate).
  const RenderedMetric metric = rendered_metric(plan);  // encodes and measures in it
  if (!plan.compressor->exact())
    data.compressed =
        compress_stage(plan, data.transfer, data.mesh, scene.compressor.where, metric);
  baked.encode_seconds = clock.seconds();
  data.compressor = plan.compressor_record;
  const std::vector<double> errors = vertex_errors(data.transfer, data.compressed, &metric);
  baked.se = std::accumulate(errors.begin(), errors.end(), 0.0);
  const fs::path bake_file = out / "bake.h5";
  write_bake(bake_file, data);
  baked.file_bytes = double(fs::file_size(bake_file));
  // What rendering needs: the compressed form (the file also keeps the exact transfer).
  baked.bytes = 4.0 * data.compressed.stored_floats();
  fs::remove(bake_file);
  return baked;
}

// Errors against the ground truth, averaged over the lights, and the images.
struct Measured {
  double relight_seconds = 0, gpu_seconds = 0;
  double rms = 0, p99 = 0, max_error = 0, image_error = 0;
  double truncation_rms = 0, projection_rms = 0, compression_rms = 0;  // the error budget
  double noise_floor = 0;  // the ground truth's standard error (per-vertex RMS), mean over lights
};

// The images of light 0: the configuration's, the truth's, their difference.
void write_images(const Image& image, const Image& truth_image, const SceneSpec& scene,
                  const fs::path& out, const std::string& label) {
  const float exposure = static_cast<float>(keys::camera::exposure(scene.camera));
  write_png(image, out / "images" / (stem_of(label) + ".png"), exposure);
  write_png(truth_image, out / "images" / "ground_truth.png", exposure);
  Image difference = image;
  for (std::size_t k = 0; k < difference.rgb.size(); ++k)
    difference.rgb[k] = 4.f * std::abs(image.rgb[k] - truth_image.rgb[k]);
  write_png(difference, out / "images" / (stem_of(label) + ".error.png"), exposure);
}

// A fresh GPU renderer's draw time (each configuration uploads its own data).
// The scene's renderer when it draws on the GPU, else the first that does.
double gpu_draw_seconds(PluginRegistry& registry, const std::string& scene_renderer,
                        RenderInput input) {
  Params defaults;
  auto gpu = registry.create<Renderer>(gpu_renderer(registry, scene_renderer), defaults);
  input.background = nullptr;  // the transfer's draw alone
  gpu->render(input);          // uploads, compiles
  gpu->render(input);
  return gpu->statistics().at("draw_seconds");
}

// Per-vertex radiance drawn by `renderer` (the ground truth's image).
Image render_radiance(Renderer& renderer, const Mesh& mesh, const Eigen::MatrixX3f& radiance,
                      const Camera& camera) {
  RenderInput input;
  input.mesh = &mesh;
  input.vertex_radiance = &radiance;
  input.camera = camera;
  return renderer.render(input);
}

// 4. Lights: the scene's and rotated copies; relight time, errors, images.
Measured measure_lights(Context& context, const BenchArgs& args, const SceneSpec& scene,
                        const BakeData& data, const std::vector<Override>& config, Reused& reused,
                        const fs::path& out, const std::string& label) {
  const Relighting relighting(scene, data, context.registry);
  // The lights turn by the viewer's rule (prt/turning_light.hpp).
  TurningLight turning(relighting, scene.load_environment());
  const Camera camera = scene.make_camera(data.mesh);
  const std::string truth_key =
      key_of(config, {"mesh", "material", "lighting", "camera", "ground_truth", "transport"});
  const std::string limited_key =
      truth_key + " " + key_of(config, {"basis", "exit", "transport", "material"});
  Params renderer_params = scene.renderer.params;
  auto cpu =
      context.registry.create<Renderer>(scene.renderer.name, renderer_params, scene.renderer.where);
  const CompressedTransfer exact_transfer = exact_form(data.transfer);  // for the budget
  const RelightKernel kernel = relighting.prepare(data.compressed);     // laid out once
  const RelightKernel exact_kernel = relighting.prepare(exact_transfer);
  const RunOptions quiet{true};
  Measured m;
  for (int light = 0; light < args.lights; ++light) {
    const Eigen::MatrixX3d l = turning.at(360.0 * light / args.lights);
    Relit relit;
    m.relight_seconds += median_seconds(3, [&] { relit = relighting.relight(kernel, l, camera); });
    auto& truth_list = reused.truths[truth_key];
    if (static_cast<int>(truth_list.size()) <= light) {
      SceneSpec rotated = scene;
      rotated.lighting.set(keys::lighting::rotation.name(),
                           keys::lighting::rotation(scene.lighting) + 360.0 * light / args.lights);
      truth_list.push_back(reference_radiance(rotated, data.mesh, rotated.load_environment(),
                                              camera, quiet, reused.cache.get()));
    }
    const Reference& truth = truth_list[light];
    m.noise_floor += truth.noise_floor() / args.lights;
    const ErrorStats e = vertex_error(relit.vertex_radiance, truth.radiance);
    m.rms += e.rms / args.lights, m.p99 += e.p99 / args.lights;
    // Error budget: light truncation, transfer projection, compression.
    auto& limited_list = reused.limited_truths[limited_key];
    if (static_cast<int>(limited_list.size()) <= light)
      limited_list.push_back(band_limited_truth(scene, data.mesh, relighting, turning.environment(),
                                                l, camera, quiet, reused.cache.get()));
    const Eigen::MatrixX3f exact = relighting.relight(exact_kernel, l, camera).vertex_radiance;
    const ErrorBudget budget =
        error_budget(truth.radiance, limited_list[light].radiance, exact, relit.vertex_radiance);
    m.truncation_rms += budget.truncation / args.lights;
    m.projection_rms += budget.projection / args.lights;
    m.compression_rms += budget.compression / args.lights;
    m.max_error = std::max(m.max_error, e.max);
    RenderInput input = relighting.input(data.compressed, relit, l, camera);
    input.background = nullptr;
    const Image image = cpu->render(input);
    const Image truth_image = render_radiance(*cpu, data.mesh, truth.radiance, camera);
    m.image_error += mean_absolute_difference(image, truth_image) / args.lights;
    if (light != 0) continue;
    write_images(image, truth_image, scene, out, label);
    if (args.gpu) m.gpu_seconds = gpu_draw_seconds(context.registry, scene.renderer.name, input);
  }
  m.relight_seconds /= args.lights;
  return m;
}

nlohmann::ordered_json result_line(const std::string& label, std::size_t index, const Baked& b,
                                   const Measured& m, int lights) {
  nlohmann::ordered_json record;
  record["label"] = label;
  record["image"] = stem_of(label);
  record["index"] = index;
  record["trace_seconds"] = b.trace_seconds;
  record["project_seconds"] = b.project_seconds;
  record["encode_seconds"] = b.encode_seconds;
  record["bake_seconds"] = b.trace_seconds + b.project_seconds + b.encode_seconds;
  record["bytes"] = b.bytes;
  record["file_bytes"] = b.file_bytes;
  record["bytes_per_vertex"] = b.bytes / double(b.data.mesh.vertex_count());
  record["relight_seconds"] = m.relight_seconds;
  // null unless --gpu timed it (a 0 would read as a measured frame time)
  record["gpu_frame_seconds"] =
      m.gpu_seconds > 0 ? nlohmann::ordered_json(m.gpu_seconds) : nlohmann::ordered_json();
  record["transfer_se"] = b.se;
  record["rms"] = m.rms;
  record["light_truncation_rms"] = m.truncation_rms;
  record["projection_rms"] = m.projection_rms;
  record["compression_rms"] = m.compression_rms;
  record["noise_floor"] = m.noise_floor;
  record["resolved"] = resolved(m.rms, m.noise_floor);
  record["p99"] = m.p99;
  record["max"] = m.max_error;
  record["image_error"] = m.image_error;
  record["lights"] = lights;
  return record;
}

// CSV and JSON of every configuration, in sweep order; then the report.
void write_summaries(const fs::path& out, const fs::path& results, const SceneSpec& base,
                     bool report, std::uint64_t budget) {
  std::vector<nlohmann::ordered_json> records;
  if (std::ifstream in(results); in)
    for (std::string line; std::getline(in, line);) {
      auto record = nlohmann::ordered_json::parse(line, nullptr, false);
      if (record.is_object()) records.push_back(std::move(record));
    }
  write_text_file(out / "results.json", nlohmann::ordered_json(records).dump(2) + "\n");
  write_csv(records, out / "results.csv");
  std::cout << "results: " << (out / "results.json").string() << " (" << records.size()
            << " configurations)\n";
  if (!report) return;
  const std::string command = "/usr/bin/python3 " +
                              (fs::path(PRT_SOURCE_DIR) / "scripts" / "bench_report.py").string() +
                              " " + out.string() + " \"" + base.file.filename().string() + "\"" +
                              (budget ? " --budget " + std::to_string(budget) : std::string());
  if (std::system(command.c_str()) != 0) throw Error("the report script failed: " + command);
  std::cout << "report: " << (out / "report.md").string() << "\n";
}

}  // namespace

int bench(Context& context, const BenchArgs& args) {
  Progress::set_enabled(!context.quiet);
  const SceneSpec base = SceneSpec::load(args.scene, context.registry);
  if (base.probes())  // its sweeps time and measure transfer at vertices
    throw Error(base.receivers.location(keys::receivers::kind.name()),
                "prt bench measures transfer at vertices; a probe scene is measured by `prt "
                "probes` and scripts/probe_sweep.sh (docs/receivers.md)");
  if (base.texels())
    throw Error(base.receivers.location(keys::receivers::kind.name()),
                "prt bench measures transfer at vertices; a texel scene is measured by `prt "
                "texels` and scripts/texel_sweep.sh (docs/receivers.md)");
  const fs::path out =
      args.out.empty() ? fs::path("bench_" + base.file.stem().string()) : fs::path(args.out);
  if (fs::exists(out) && !fs::is_directory(out))
    throw Error(out.string() + ": the bench output folder exists and is not a directory");

  const std::vector<std::vector<Override>> configs = configurations(args.sweeps);
  // Validate every configuration before any work; each plan serves its bake.
  std::vector<SceneSpec> scenes;
  std::vector<BakePlan> plans;
  for (const auto& config : configs) {
    try {  // every plug-in created and every parameter checked, before any ray
      scenes.push_back(SceneSpec::parse(scene_with(base.text, base.file.string(), config),
                                        base.file, context.registry));
      apply_samples(args.reference, scenes.back());
      plans.push_back(plan_bake(scenes.back(), context.registry));
    } catch (const Error& e) {
      // The swept scene is the base scene rewritten: a line of it is not a
      // line of the user's file, so the message names the --sweep instead.
      std::string message = e.what();
      const std::size_t at = message.find(": error: ");
      if (at != std::string::npos) message = message.substr(at + 9);
      throw Error(SourceLocation{base.file.string()},
                  "--sweep configuration \"" + label_of(config) + "\": " + message);
    }
  }

  fs::create_directories(out / "images");  // once every configuration is valid
  // Resume: configurations already in results.jsonl are skipped.
  const fs::path results = out / "results.jsonl";
  const std::set<std::string> done = finished_labels(results);
  std::ofstream log(results, std::ios::app);
  Reused reused;
  reused.cache = reference_cache(args.reference);
  Progress progress("bench", double(configs.size()), "", context.quiet);
  for (std::size_t i = 0; i < configs.size(); ++i) {
    const std::string label = label_of(configs[i]);
    if (!done.count(label)) {
      const Baked baked = bake_configuration(scenes[i], plans[i], configs[i], reused, out);
      const Measured measured =
          measure_lights(context, args, scenes[i], baked.data, configs[i], reused, out, label);
      log << result_line(label, i, baked, measured, args.lights).dump() << "\n" << std::flush;
      // A full disk: stop here; the lines before this one are whole, and the
      // next run resumes after them (a cut last line is run again).
      if (!log)
        throw Error(results.string() +
                    ": cannot append a result (a full disk?); the configurations before it are "
                    "kept, and the same command resumes after them");
    }
    progress.add(1);
  }
  log.close();
  write_summaries(out, results, base, !args.no_report, args.budget);
  return 0;
}

}  // namespace prt::cli
