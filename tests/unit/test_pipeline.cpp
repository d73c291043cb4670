// The bake as a plan and stages: everything is validated before a ray, and a
// sweep's reuse of traced rays gives the same transfer as a fresh bake.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdio>

#include "prt/log.hpp"
#include "prt/pipeline.hpp"
#include "prt/progress.hpp"
#include "prt/registry.hpp"
#include "prt/transport.hpp"

using namespace prt;

namespace {

const char* kScene = R"(
[mesh]
generate = "open-box"
detail = 1
[material]
brdf = "%s"
[transport]
directions = "cubemap"
rays = 384
[basis]
%s
[compressor]
plugin = "cpca"
clusters = 4
components = 2
[lighting]
constant = [1, 1, 1]
%s
)";

SceneSpec scene(PluginRegistry& registry, const char* brdf, const char* basis,
                const char* lighting = "") {
  char text[1024];
  std::snprintf(text, sizeof text, kScene, brdf, basis, lighting);
  return SceneSpec::parse(text, "pipeline.toml", registry);
}

}  // namespace

TEST_CASE("a sweep's traced rays give the same transfer as a fresh bake", "[pipeline]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Progress::set_enabled(false);
  for (const char* brdf : {"lambert", "phong"}) {
    for (const char* basis : {"plugin = \"sh\"\norder = 4", "plugin = \"eigen\"\nd = 8"}) {
      INFO(brdf << ", " << basis);
      const SceneSpec s = scene(registry, brdf, basis);
      StageTimes times;
      const BakeData fresh = bake(s, registry, {true}, times);
      const TransportResult traced = trace_scene(s, {true});
      RunOptions reuse{true, &traced};
      reuse.compress = false;
      const BakeData swept = bake(s, registry, reuse, times);
      REQUIRE(swept.transfer.dimension() == fresh.transfer.dimension());
      REQUIRE(swept.transfer.vertices() == fresh.transfer.vertices());
      CHECK((swept.transfer.coefficients - fresh.transfer.coefficients).cwiseAbs().maxCoeff() <
            1e-6f * std::max(1.f, fresh.transfer.coefficients.cwiseAbs().maxCoeff()));
      // Without compression the bake keeps the exact transfer.
      CHECK(swept.compressed.decode() == swept.transfer.coefficients);
      CHECK(fresh.compressed.clusters() == 4);
    }
  }
  Progress::set_enabled(true);
}

TEST_CASE("the plan is a value: a fit returns a new basis and leaves the plan's alone",
          "[pipeline]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Progress::set_enabled(false);
  const SceneSpec s = scene(registry, "lambert", "plugin = \"eigen\"\nd = 8");
  const BakePlan plan = plan_bake(s, registry);
  REQUIRE(plan.fit);
  StageTimes times;
  const BakeData first = bake(s, plan, {true}, times);
  // The plan's basis is unfitted after the bake; the file has the fitted state.
  CHECK_THROWS_WITH(plan.basis->save(), Catch::Contains("not fitted"));
  CHECK_FALSE(first.basis_state.matrices.empty());
  // So the same plan bakes again to the same bits (nothing carried over).
  const BakeData second = bake(s, plan, {true}, times);
  CHECK(second.transfer.coefficients == first.transfer.coefficients);
  CHECK(second.basis_state.matrices == first.basis_state.matrices);
  // Stage 2 returns the fitted basis, its times and its rays.
  const TransferOutcome outcome =
      transfer_stage(plan, s.load_mesh(), s.directions(),
                     trace_stage(plan, s.load_mesh(), s.directions(), {true}), {true});
  CHECK(outcome.basis != plan.basis);
  CHECK(outcome.basis->save().matrices == first.basis_state.matrices);
  CHECK(outcome.rays_cast > 0);
  CHECK_FALSE(outcome.times.stages.empty());
  Progress::set_enabled(true);
}

TEST_CASE("the plan refuses what cannot work before any ray", "[pipeline]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  // A window needs frequency bands; Haar has none.
  CHECK_THROWS_WITH(plan_bake(scene(registry, "lambert", "plugin = \"haar\"\nresolution = 4",
                                    "window = \"hanning\""),
                              registry),
                    Catch::Contains("pipeline.toml:") && Catch::Contains("window") &&
                        Catch::Contains("coefficient_bands"));
  // A non-linear approximation replaces compression: an exact compressor only.
  CHECK_THROWS_WITH(
      plan_bake(scene(registry, "lambert", "plugin = \"haar\"\nresolution = 4\nk = 8"), registry),
      Catch::Contains("exact compressor") && Catch::Contains("cpca"));
  // A basis that needs a cube map says so before the rays, at [transport].
  std::string fibonacci =
      "\n[mesh]\ngenerate = \"sphere\"\n[transport]\nrays = 96\n[basis]\n"
      "plugin = \"eigen\"\nd = 4\n[lighting]\nconstant = [1, 1, 1]\n";
  CHECK_THROWS_WITH(plan_bake(SceneSpec::parse(fibonacci, "eigen.toml", registry), registry),
                    Catch::Contains("eigen.toml:") && Catch::Contains("cube-map direction set"));
  CHECK_NOTHROW(plan_bake(
      scene(registry, "lambert", "plugin = \"sh\"\norder = 3", "window = \"hanning\""), registry));
}

TEST_CASE("progress and messages reach the app's callbacks, not the terminal", "[pipeline]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  std::vector<ProgressReport> reports;
  std::vector<std::string> messages;
  Progress::set_enabled(true);
  Progress::set_sink([&](const ProgressReport& r) { reports.push_back(r); });
  struct Reset {  // the sink refers to locals: reset it however the test ends
    ~Reset() { Progress::set_sink(nullptr); }
  } reset;
  RunOptions options;
  options.log = [&](const std::string& text) { messages.push_back(text); };
  StageTimes times;
  const BakeData data =
      bake(scene(registry, "lambert", "plugin = \"sh\"\norder = 3"), registry, options, times);
  Progress::set_sink(nullptr);
  const auto final_bake = std::find_if(reports.begin(), reports.end(), [](const auto& r) {
    return r.label == "bake transfer" && r.final;
  });
  REQUIRE(final_bake != reports.end());
  CHECK(final_bake->done == double(data.mesh.vertex_count()));
  CHECK(final_bake->unit == "rays");
  REQUIRE(!messages.empty());
  CHECK(messages.back().find("SE") != std::string::npos);
}

TEST_CASE("library warnings reach the app's log sink", "[pipeline]") {
  std::vector<std::pair<LogLevel, std::string>> lines;
  set_log_sink([&](LogLevel level, const std::string& text) { lines.emplace_back(level, text); });
  struct Reset {
    ~Reset() { set_log_sink(nullptr); }
  } reset;
  RunOptions options;
  options.warn("a test warning");
  options.message("a test message");
  set_log_sink(nullptr);
  REQUIRE(lines.size() == 2);
  CHECK(lines[0] == std::pair{LogLevel::warning, std::string("a test warning")});
  CHECK(lines[1] == std::pair{LogLevel::info, std::string("a test message")});
}
