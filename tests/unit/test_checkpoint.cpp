// Checkpoints: parts are kept whole or not at all, damage and a changed run
// are refused, and a bake through a checkpoint (in slabs, resumed after parts
// were lost) equals the bake without one, bit for bit.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "prt/checkpoint.hpp"
#include "prt/error.hpp"
#include "prt/pipeline.hpp"
#include "prt/progress.hpp"
#include "prt/registry.hpp"
#include "prt/visible_products.hpp"

using namespace prt;
namespace fs = std::filesystem;

namespace {

fs::path fresh_folder(const std::string& name) {
  const fs::path folder = fs::temp_directory_path() / ("prt_checkpoint_" + name);
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

// "what.rows-FIRST-LAST": the name of a slab's part.
std::string part_name(const char* what, std::size_t first, std::size_t last) {
  char name[96];
  std::snprintf(name, sizeof name, "%s.rows-%012zu-%012zu", what, first, last);
  return name;
}

// How many of a checkpoint's parts have names that start with `prefix`.
long parts_named(const std::vector<std::string>& parts, const std::string& prefix) {
  return long(std::count_if(parts.begin(), parts.end(),
                            [&](const std::string& p) { return p.rfind(prefix, 0) == 0; }));
}

SceneSpec scene(PluginRegistry& registry, const std::string& material, const std::string& basis) {
  const std::string text = R"(
[mesh]
generate = "open-box"
detail = 1
[material]
)" + material + R"(
[transport]
rays = 128
[basis]
)" + basis + R"(
[exit]
plugin = "hsh"
order = 3
[compressor]
plugin = "cpca"
clusters = 8
components = 2
[lighting]
constant = [1.0, 0.7, 0.4]
)";
  return SceneSpec::parse(text, "checkpoint.toml", registry);
}

}  // namespace

TEST_CASE("checkpoint parts round-trip and refuse damage and other runs", "[checkpoint]") {
  const fs::path output = fresh_folder("store") / "bake.h5";
  const CheckpointStore store(output, "key-1", "test");
  MatrixXfRow floats = MatrixXfRow::Random(5, 3);
  Eigen::MatrixXd doubles = Eigen::MatrixXd::Random(2, 4);
  store.save("floats", floats);
  store.save("doubles", doubles);
  store.save("ints", std::vector<std::int32_t>{3, -1, 7});
  store.save_text("text", "a 1\nb 2.5\n");
  CHECK(store.load_floats("floats") == floats);
  CHECK(store.load_doubles("doubles") == doubles);
  CHECK(store.load_ints("ints") == std::vector<std::int32_t>{3, -1, 7});
  CHECK(store.load_text("text") == "a 1\nb 2.5\n");
  CHECK(store.parts() == std::vector<std::string>{"doubles", "floats", "ints", "text"});
  // While it is held, a second opening is refused (its lock); a read-only
  // sharer (another rank) may open it.
  CHECK_THROWS_WITH(CheckpointStore(output, "key-1", "test"),
                    Catch::Contains("another prt process is using this checkpoint"));
  CHECK_THROWS_WITH(CheckpointStore::discard(output), Catch::Contains("another prt process"));
  CHECK_NOTHROW(CheckpointStore(output, "key-1", "test", false));
  // Another run is refused with the folder's name, even when unlocked.
  CHECK_THROWS_WITH(CheckpointStore(output, "key-2", "test", false),
                    Catch::Contains(".bake.h5.checkpoint") && Catch::Contains("--restart"));
  // A truncated part and a flipped byte are refused, not loaded.
  const fs::path part = store.folder() / "floats";
  fs::resize_file(part, fs::file_size(part) - 4);
  CHECK_THROWS_WITH(store.load_floats("floats"), Catch::Contains("damaged"));
  {
    std::fstream file(store.folder() / "doubles", std::ios::in | std::ios::out | std::ios::binary);
    file.seekp(-1, std::ios::end);
    file.put('\x5a');
  }
  CHECK_THROWS_WITH(store.load_doubles("doubles"), Catch::Contains("damaged"));
  CHECK_THROWS(store.load_floats("ints"));  // wrong type
  store.remove();
  CHECK_FALSE(fs::exists(store.folder()));
}

TEST_CASE("a released checkpoint reopens for the same run and is discarded on request",
          "[checkpoint]") {
  const fs::path output = fresh_folder("reopen") / "bake.h5";
  { CheckpointStore(output, "key-1", "test").save_text("part", "x"); }
  {
    const CheckpointStore again(output, "key-1", "test");
    CHECK(again.load_text("part") == "x");
  }
  CHECK_THROWS_WITH(CheckpointStore(output, "key-2", "test"), Catch::Contains("--restart"));
  CheckpointStore::discard(output);
  CHECK_FALSE(fs::exists(CheckpointStore::folder_for(output)));
  CHECK_NOTHROW(CheckpointStore(output, "key-2", "test"));
}

TEST_CASE("a bake in slabs through a checkpoint equals the bake without one", "[checkpoint]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Progress::set_enabled(false);
  const std::string sh = "plugin = \"sh\"\norder = 4";
  for (const std::string& material :
       {std::string("albedo = 0.8"),
        std::string("brdf = \"phong\"\nspecular = 0.5\nexponent = 8")}) {
    INFO(material);
    const SceneSpec s = scene(registry, material, sh);
    StageTimes times;
    const BakeData reference = bake(s, registry, {true}, times);
    const fs::path output = fresh_folder("slabs") / "bake.h5";
    const BakePlan plan = plan_bake(s, registry);
    REQUIRE(per_vertex_transfer(plan));
    const CheckpointStore store(output, bake_key(s, plan), "test");
    RunOptions options{true};
    options.checkpoint = &store;
    // 100 vertices, rounded up to a block of the projection: several slabs,
    // the last one short.
    options.slab_vertices = 100;
    const std::size_t v = reference.mesh.vertex_count();
    REQUIRE(v > kProjectionBlock);
    REQUIRE(v % kProjectionBlock != 0);
    const BakeData slabbed = bake(s, registry, options, times);
    CHECK(slabbed.transfer.coefficients == reference.transfer.coefficients);
    CHECK(slabbed.transfer.kind == reference.transfer.kind);
    CHECK(slabbed.transfer.exit_rows == reference.transfer.exit_rows);
    CHECK(slabbed.compressed.cluster_of_vertex == reference.compressed.cluster_of_vertex);
    CHECK(slabbed.metrics == reference.metrics);
    // Lose two slabs (as a kill would have left them never written): the
    // rerun computes them again and gets the same result.
    REQUIRE(fs::remove(store.folder() / part_name("transfer", 0, kProjectionBlock)));
    REQUIRE(
        fs::remove(store.folder() / part_name("rays", v / kProjectionBlock * kProjectionBlock, v)));
    const BakeData resumed = bake(s, registry, options, times);
    CHECK(resumed.transfer.coefficients == reference.transfer.coefficients);
    CHECK(resumed.metrics == reference.metrics);
  }
}

TEST_CASE("a fitted basis keeps its bits, state and rows in the checkpoint and resumes from them",
          "[checkpoint]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Progress::set_enabled(false);
  std::string text = R"(
[mesh]
generate = "open-box"
detail = 1
[transport]
directions = "cubemap"
rays = 384
[basis]
plugin = "eigen"
d = 8
[compressor]
plugin = "pca"
components = 4
[lighting]
constant = [1, 1, 1]
)";
  const SceneSpec s = SceneSpec::parse(text, "eigen.toml", registry);
  StageTimes times;
  const BakeData reference = bake(s, registry, {true}, times);
  const fs::path output = fresh_folder("fitted") / "bake.h5";
  const BakePlan plan = plan_bake(s, registry);
  REQUIRE_FALSE(per_vertex_transfer(plan));
  REQUIRE(fitted_per_vertex_transfer(plan));
  const CheckpointStore store(output, bake_key(s, plan), "test");
  RunOptions options{true};
  options.checkpoint = &store;
  options.slab_vertices = 100;  // several slabs of bits
  const BakeData first = bake(s, registry, options, times);
  const auto parts = store.parts();
  const auto count = [&](const std::string& prefix) { return parts_named(parts, prefix); };
  CHECK(count("bits.rows-") > 1);
  CHECK(count("eigen.z.") > 0);  // a state per power iteration
  REQUIRE(store.has("fitted-basis"));
  REQUIRE(count("transfer.rows-") == 1);
  const BakeData resumed = bake(s, registry, options, times);  // loads, traces nothing
  // Killed after the fit, before the rows were kept: the basis is loaded,
  // the rows projected from the kept bits.
  for (const auto& part : parts)
    if (part.rfind("transfer.rows-", 0) == 0) fs::remove(store.folder() / part);
  const BakeData reprojected = bake(s, registry, options, times);
  for (const BakeData* data : {&first, &resumed, &reprojected}) {
    CHECK(data->transfer.coefficients == reference.transfer.coefficients);
    CHECK(data->basis_state.matrices == reference.basis_state.matrices);
    CHECK(data->metrics == reference.metrics);
  }
}

TEST_CASE("a bake that couples vertices keeps its stages in slabs and resumes from them",
          "[checkpoint]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Progress::set_enabled(false);
  // Three channel transfers (a coloured kd with bounces), each with two
  // bounces and subsurface light; and a glossy one with a bounce.
  for (const std::string& material :
       {std::string("diffuse = [0.9, 0.5, 0.2]\nsubsurface = true"),
        std::string("brdf = \"phong\"\ndiffuse = [0.6, 0.3, 0.3]\nspecular = 0.4\nexponent = 8")}) {
    INFO(material);
    const SceneSpec s = SceneSpec::parse(R"(
[mesh]
generate = "open-box"
detail = 1
[material]
)" + material + R"(
[transport]
rays = 128
bounces = 2
[basis]
plugin = "sh"
order = 3
[exit]
plugin = "hsh"
order = 2
[compressor]
plugin = "pca"
components = 2
[lighting]
constant = [1.0, 0.7, 0.4]
)",
                                         "coupled.toml", registry);
    StageTimes times;
    const BakeData reference = bake(s, registry, {true}, times);
    const fs::path output = fresh_folder("coupled") / "bake.h5";
    const BakePlan plan = plan_bake(s, registry);
    REQUIRE_FALSE(per_vertex_transfer(plan));
    const CheckpointStore store(output, bake_key(s, plan), "test");
    RunOptions options{true};
    options.checkpoint = &store;
    options.slab_vertices = 100;  // the trace's slabs: rounded up to a block of the projection
    const BakeData first = bake(s, registry, options, times);
    const auto parts = store.parts();
    const auto count = [&](const std::string& prefix) { return parts_named(parts, prefix); };
    const std::size_t v = reference.mesh.vertex_count();
    const auto slabs = (v + kProjectionBlock - 1) / kProjectionBlock;
    REQUIRE(slabs > 1);
    CHECK(count("trace-rays.rows-") == long(slabs));
    CHECK(count("trace-hits.rows-") == long(slabs));
    const long channels = long(plan.channels.groups.size());
    REQUIRE(channels > 1);
    for (long g = 1; g <= channels; ++g) {
      const std::string prefix = "channel-" + std::to_string(g) + ".";
      CHECK(store.has(prefix + "transfer"));
      CHECK(count(prefix + "bounce-") == 0);  // the stages' parts go once the channel is kept
      CHECK(count(prefix + "glossy.") == 0);
    }
    REQUIRE(store.has("transfer"));
    // Killed before the last channel was kept, and before a slab of the
    // trace was: the rerun traces that slab and computes that channel again.
    const std::string last = "channel-" + std::to_string(channels) + ".transfer";
    for (const std::string& lost :
         {std::string("transfer"), last,
          part_name("trace-rays", kProjectionBlock, std::min(v, 2 * kProjectionBlock))})
      REQUIRE(fs::remove(store.folder() / lost));
    const BakeData resumed = bake(s, registry, options, times);
    for (const BakeData* data : {&first, &resumed}) {
      CHECK(data->transfer.coefficients == reference.transfer.coefficients);
      CHECK(data->transfer.channel_groups == reference.transfer.channel_groups);
      CHECK(data->compressed.weights == reference.compressed.weights);
      CHECK(data->metrics == reference.metrics);
    }
    // Damaged hits (a triangle the mesh does not have) are refused.
    std::vector<std::int32_t> hits(kProjectionBlock, 0);
    hits[0] = 1;
    hits.insert(hits.end(), {0, 1 << 30, 0, 0});
    REQUIRE(fs::remove(store.folder() / "transfer"));
    const std::string damaged = part_name("trace-hits", 0, kProjectionBlock);
    store.save(damaged, hits);
    CHECK_THROWS_WITH(bake(s, registry, options, times),
                      Catch::Contains(damaged) && Catch::Contains("--restart"));
    store.remove();
  }
}
