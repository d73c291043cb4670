// The prt command-line tool's subcommands. Each returns the process exit code;
// errors are thrown as prt::Error and reported by main.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "../common/bake_command.hpp"
#include "prt/registry.hpp"

namespace prt::cli {

// Owned by main: the plug-in registry and global options.
struct Context {
  PluginRegistry registry;
  bool quiet = false;
};

int bake(Context& context, const BakeArgs& args);

// How the Monte Carlo reference is made and kept (render --compare, bench,
// compare-bases): reference_options.cpp.
struct ReferenceArgs {
  std::int64_t samples = 0;  // 0: the scene's [ground_truth] samples
  std::string cache;         // "": ReferenceCache::default_folder()
  bool no_cache = false;
};

struct RenderArgs {
  std::string scene, bake, output;
  bool ground_truth = false, compare = false, force = false;
  bool no_budget = false;  // --compare without the error budget (its second ground truth)
  float exposure = 0.0f;   // 0: the scene's [camera] exposure
  std::string renderer;    // overrides the scene's [renderer] plugin
  std::vector<std::string> renderer_parameters;  // key=value for it
  ReferenceArgs reference;
};
int render(Context& context, const RenderArgs& args);

// prt probes: probes.cpp.
struct ProbesArgs {
  std::string scene, bake, out;
  std::vector<std::string> at;  // x,y,z positions of the moving object
  ReferenceArgs reference;
};
int probes(Context& context, const ProbesArgs& args);

// prt texels: texels.cpp.
struct TexelsArgs {
  std::string scene, out;
  std::vector<std::int64_t> resolutions;  // atlas resolutions (default: the scene's)
  std::int64_t points = 20000;            // surface points the error is measured at
  ReferenceArgs reference;
};
int texels(Context& context, const TexelsArgs& args);

struct CompressArgs {
  std::string bake, output, compressor;  // no default: the one default is the scene's ("none")
  std::vector<std::string> parameters;   // key=value
  bool json = false, force = false;
  std::uint64_t memory = 0;  // memory budget in bytes (0: the default share of RAM)
  // "plugin k=v|plugin k=v" (repeatable): many encodings ranked, none written.
  std::vector<std::string> sweeps;
  std::vector<std::uint64_t> budgets;  // bytes: the best configuration within each
};
int compress(Context& context, const CompressArgs& args);
int compress_sweep(Context& context, const CompressArgs& args);

struct SubdivideArgs {
  std::string input, output, scheme = "loop";
  std::size_t vertices = 0;
  bool force = false;
};
int subdivide(const SubdivideArgs& args);

struct AnalyzeArgs {
  int order = 5;
  double cutoff = 1e-10;
  std::vector<int> odd_orders{8}, even_orders{5, 7};
  bool json = false;
};
int analyze_hemisphere(const AnalyzeArgs& args);

struct BenchArgs {
  std::string scene, out;
  std::vector<std::string> sweeps;  // section.key=v1,v2,...
  int lights = 2;                   // the scene's light plus rotated copies
  bool gpu = false, no_report = false, force = false;
  std::uint64_t budget = 0;  // bytes of the compressed form the report recommends within (0: any)
  ReferenceArgs reference;
};
int bench(Context& context, const BenchArgs& args);

struct StabilityArgs {
  std::vector<int> orders{2, 5, 10, 15, 20, 30, 40, 50, 60, 70, 80, 90, 101, 120, 150};
  int max_rotation_order = 101;
  // Single bands measured alone (rotation and the addition theorem) to high degree.
  std::vector<int> bands{100, 200, 500, 1000};
  int hemisphere_order = 12;
  std::string json, figure_data;
  bool force = false;
};
int stability(Context& context, const StabilityArgs& args);

struct CompareArgs {
  std::string scene, bases, csv, json;
  bool force = false;
  ReferenceArgs reference;
};
int compare_bases(Context& context, const CompareArgs& args);

// Prints the mean absolute difference of two PNGs and the share of pixels
// differing by more than 8 levels in some channel.
int image_diff(const std::string& a, const std::string& b);

// "key=value" typed as TOML would type it, located at command-line item `index`.
void parse_parameter(const std::string& text, std::size_t index, Params& params);

int info(Context& context, const std::string& bake_file);
int plugins(Context& context);

struct DemoArgs {
  std::string scene;
};
int demo(Context& context, const DemoArgs& args);

// The median wall time of `runs` calls of `work` (bench, compare-bases).
double median_seconds(int runs, const std::function<void()>& work);

}  // namespace prt::cli
