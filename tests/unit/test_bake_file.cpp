#include <H5Cpp.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "../../framework/src/bake_userblock.hpp"
#include "prt/bake_file.hpp"
#include "prt/error.hpp"
#include "prt/output_file.hpp"
#include "prt/pipeline.hpp"
#include "prt/progress.hpp"
#include "prt/registry.hpp"

using namespace prt;
namespace fs = std::filesystem;

namespace {
// One folder per test case: ctest runs the cases in parallel processes.
fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("prt_bake_tests_" + name);
  fs::create_directories(dir);
  return dir;
}

BakeData sample_bake() {
  BakeData d;
  d.scene_file = "scene.toml";
  d.scene_text = "[basis]\nplugin = \"sh\"\n";
  d.basis = {"sh", "1.0.0", "order = 3\n"};
  d.compressor = {"none", "1.0.0", ""};
  d.transport = "fibonacci 64 directions";
  d.mesh = make_box();
  d.albedo = {0.5f, 0.25f, 1.0f};
  d.transfer.coefficients = MatrixXfRow::Random(d.mesh.vertex_count(), 9);
  d.compressed.compressor = "none";
  d.compressed.dimension = 9;
  d.compressed.components = 2;
  d.compressed.cluster_of_vertex.assign(d.mesh.vertex_count(), 1);
  d.compressed.cluster_of_vertex[0] = 0;
  d.compressed.weights = MatrixXfRow::Random(d.mesh.vertex_count(), 2);
  d.compressed.means = MatrixXfRow::Random(2, 9);
  d.compressed.representatives = {MatrixXfRow::Random(2, 9), MatrixXfRow::Random(2, 9)};
  d.basis_state.matrices["mean"] = Eigen::MatrixXd::Random(3, 4);
  d.metrics["trace_seconds"] = 1.5;
  return d;
}

bool leftovers(const fs::path& file) {
  const std::string prefix = "." + file.filename().string() + ".tmp-";
  for (const auto& e : fs::directory_iterator(file.parent_path()))
    if (e.path().filename().string().rfind(prefix, 0) == 0) return true;
  return false;
}
}  // namespace

TEST_CASE("bake files round-trip every field", "[bake]") {
  const BakeData d = sample_bake();
  const fs::path file = temp_dir("roundtrip") / "roundtrip.h5";
  write_bake(file, d);
  const BakeData r = read_bake(file);
  CHECK(r.scene_text == d.scene_text);
  CHECK(r.basis.name == d.basis.name);
  CHECK(r.basis.parameters == d.basis.parameters);
  CHECK(r.compressor.parameters.empty());
  CHECK(r.transport == d.transport);
  CHECK(r.mesh.positions == d.mesh.positions);
  CHECK(r.mesh.triangles == d.mesh.triangles);
  CHECK(r.albedo == d.albedo);
  CHECK(r.transfer.coefficients == d.transfer.coefficients);
  CHECK(r.compressed.cluster_of_vertex == d.compressed.cluster_of_vertex);
  CHECK(r.compressed.weights == d.compressed.weights);
  CHECK(r.compressed.means == d.compressed.means);
  CHECK(r.compressed.representatives[1] == d.compressed.representatives[1]);
  CHECK(r.basis_state.matrices.at("mean") == d.basis_state.matrices.at("mean"));
  CHECK(r.metrics.at("trace_seconds") == 1.5);
  CHECK_FALSE(leftovers(file));
}

TEST_CASE("a failed write leaves neither the file nor a temporary", "[bake]") {
  const fs::path file = temp_dir("failed") / "never.h5";
  fs::remove(file);
  CHECK_THROWS(write_atomically(file, [](const fs::path& temporary) {
    std::ofstream(temporary) << "half";
    throw Error("interrupted");
  }));
  CHECK_FALSE(fs::exists(file));
  CHECK_FALSE(leftovers(file));
}

TEST_CASE("channel transfers that do not fit their columns are never written", "[bake][colour]") {
  const fs::path file = temp_dir("channels") / "channels.h5";
  fs::remove(file);
  BakeData d = sample_bake();
  d.transfer.channel_groups = 2;
  d.transfer.group_of_channel = {0, 1, 1};
  if (d.transfer.dimension() % 2 == 0) d.transfer.channel_groups = 3;  // never divides evenly
  CHECK_THROWS_WITH(write_bake(file, d), Catch::Contains("do not fit together"));
  d.transfer.channel_groups = 1;
  d.transfer.group_of_channel = {0, 0, 1};  // channel 2 reads a missing transfer
  CHECK_THROWS_WITH(write_bake(file, d), Catch::Contains("missing"));
  CHECK_FALSE(fs::exists(file));
  CHECK_FALSE(leftovers(file));
}

TEST_CASE("a failed rewrite keeps the previous complete file", "[bake]") {
  const fs::path file = temp_dir("keep") / "keep.h5";
  write_bake(file, sample_bake());
  BakeData broken = sample_bake();
  broken.compressed.representatives.pop_back();  // inconsistent: cannot be written
  CHECK_THROWS(write_bake(file, broken));
  CHECK_NOTHROW(read_bake(file));
}

TEST_CASE("damaged and foreign files are refused with a clear message", "[bake]") {
  const fs::path dir = temp_dir("damaged");
  CHECK_THROWS_WITH(read_bake(dir / "missing.h5"), Catch::Contains("not found"));

  std::ofstream(dir / "garbage.h5") << "definitely not hdf5";
  CHECK_THROWS_WITH(read_bake(dir / "garbage.h5"),
                    Catch::Contains("garbage.h5") && Catch::Contains("not a PRT bake file"));

  write_bake(dir / "whole.h5", sample_bake());
  const auto size = fs::file_size(dir / "whole.h5");
  fs::copy_file(dir / "whole.h5", dir / "truncated.h5", fs::copy_options::overwrite_existing);
  fs::resize_file(dir / "truncated.h5", size / 2);
  CHECK_THROWS_WITH(read_bake(dir / "truncated.h5"), Catch::Contains("truncated.h5"));

  { H5::H5File other((dir / "other.h5").string(), H5F_ACC_TRUNC); }
  CHECK_THROWS_WITH(read_bake(dir / "other.h5"), Catch::Contains("not a PRT bake"));

  fs::copy_file(dir / "whole.h5", dir / "future.h5", fs::copy_options::overwrite_existing);
  seal_bake_file(dir / "future.h5", 99);  // a well-formed file of a later format
  CHECK_THROWS_WITH(read_bake(dir / "future.h5"),
                    Catch::Contains("format version 99") &&
                        Catch::Contains("reads versions " + std::to_string(kBakeFormatVersion) +
                                        " and " + std::to_string(kReceiversFormatVersion)));
  // A bake at vertices sealed as a probe bake (version 5): the header and the
  // file's own format_version attribute must agree.
  fs::copy_file(dir / "whole.h5", dir / "relabelled.h5", fs::copy_options::overwrite_existing);
  seal_bake_file(dir / "relabelled.h5", kReceiversFormatVersion);
  CHECK_THROWS_WITH(read_bake(dir / "relabelled.h5"),
                    Catch::Contains("relabelled.h5") && Catch::Contains("disagree"));
}

TEST_CASE("the same scene and seed bake to bit-identical files", "[bake_file][reproducibility]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  Progress::set_enabled(false);
  const std::string text = R"(
[mesh]
generate = "open-box"
detail = 1
[material]
albedo = [0.7, 0.7, 0.7]
[transport]
directions = "stratified"
rays = 512
seed = 3
bounces = 1
[basis]
plugin = "sh"
order = 4
[compressor]
plugin = "cpca"
method = "iterative"
clusters = 8
components = 3
reclassify = true
supercluster = "greedy"
[lighting]
constant = [1, 1, 1]
)";
  const SceneSpec scene = SceneSpec::parse(text, "repro.toml", registry);
  const fs::path dir = fs::temp_directory_path() / "prt_reproducibility";
  fs::create_directories(dir);
  auto bytes_of = [](const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  std::string first;
  for (int run = 0; run < 2; ++run) {
    StageTimes times;
    const fs::path file = dir / ("bake" + std::to_string(run) + ".h5");
    write_bake(file, bake(scene, registry, {true}, times));
    if (run == 0)
      first = bytes_of(file);
    else
      CHECK(bytes_of(file) == first);
  }
  Progress::set_enabled(true);
  fs::remove_all(dir);
}
