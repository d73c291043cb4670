#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "prt/basis.hpp"
#include "prt/registry.hpp"

using namespace prt;
namespace fs = std::filesystem;

namespace {
fs::path case_dir(const std::string& name) {
  return fs::path(PRT_TEST_PLUGIN_DIR) / name;
}

bool is_mapped(const std::string& fragment) {
  std::ifstream maps("/proc/self/maps");
  std::stringstream text;
  text << maps.rdbuf();
  return text.str().find(fragment) != std::string::npos;
}
}  // namespace

TEST_CASE("the build's plug-ins are discovered from their info records", "[registry]") {
  PluginRegistry r({PRT_BUILD_PLUGIN_DIR});
  CHECK(r.names(PluginKind::basis) == std::vector<std::string>{"eigen", "haar", "hsh", "sg", "sh"});
  CHECK(r.names(PluginKind::compressor) == std::vector<std::string>{"cpca", "none", "pca", "vq"});
  CHECK(r.names(PluginKind::renderer) == std::vector<std::string>{"cpu", "opengl"});
  const auto& sh = r.find(PluginKind::basis, "sh");
  CHECK(r.find(PluginKind::basis, "hsh").schema().find("cutoff") != nullptr);
  CHECK(std::string(sh.info.build_key) == host_build_key());
  CHECK(sh.schema().find("order") != nullptr);
  CHECK(r.loaded_count() == 0);  // reading records loads nothing
}

TEST_CASE("a library is loaded only when an object is created", "[registry]") {
  PluginRegistry r({case_dir("good")});
  CHECK(r.loaded_count() == 0);
  CHECK_FALSE(is_mapped("libprt-basis-good.so"));
  Params p;
  auto basis = r.create<Basis>("constant", p);
  CHECK(r.loaded_count() == 1);
  CHECK(is_mapped("libprt-basis-good.so"));
  CHECK(basis->size() == 1);
}

TEST_CASE("objects keep their library mapped after the registry is gone", "[registry][lifetime]") {
  std::shared_ptr<Basis> basis;
  {
    PluginRegistry r({case_dir("good")});
    Params p;
    p.set("scale", 2.0);
    basis = r.create<Basis>("constant", p);
  }
  // The registry's handle is gone; calling into the plug-in must still work.
  REQUIRE(is_mapped("libprt-basis-good.so"));
  const Eigen::MatrixXd v = basis->evaluate(Directions::Zero(3, 3));
  CHECK(v(0, 0) == Approx(2.0 / std::sqrt(4 * M_PI)));
  basis.reset();  // destroy runs inside the module, then the module is unmapped
  CHECK_FALSE(is_mapped("libprt-basis-good.so"));
}

TEST_CASE("plug-in parameters are validated against the schema before creation", "[registry]") {
  PluginRegistry r({case_dir("good")});
  Params p({"s.toml", 3, 1});
  p.set("scael", 1.0, {"s.toml", 4, 1});
  CHECK_THROWS_WITH(r.create<Basis>("constant", p),
                    Catch::Contains("s.toml:4:1") && Catch::Contains("did you mean \"scale\""));
  CHECK(r.loaded_count() == 0);
}

namespace {
// The one message a registry over `dir` recorded while skipping its files.
std::string problem_in(const fs::path& dir) {
  PluginRegistry r({dir});
  REQUIRE(r.problems().size() == 1);
  return r.problems()[0].message;
}
}  // namespace

TEST_CASE("each plug-in failure gives one clear error naming the file", "[registry]") {
  using Catch::Contains;
  CHECK_THAT(problem_in(case_dir("not_a_plugin")),
             Contains("libprt-basis-notaplugin.so: not a PRT plug-in"));
  CHECK_THAT(
      problem_in(case_dir("missing_symbol")),
      Contains("libprt-basis-missing.so") && Contains("lacks the symbol prt_plugin_destroy"));
  CHECK_THAT(problem_in(case_dir("abi_mismatch")),
             Contains("libprt-basis-abi.so: plug-in ABI version 999") &&
                 Contains("this host reads ABI version 1"));
  // The one component that differs is named.
  CHECK_THAT(problem_in(case_dir("build_key")),
             Contains("libprt-basis-key.so") &&
                 Contains("was built with align = 8, but this host has align = 64") &&
                 Contains(host_build_key()));
  CHECK_THAT(problem_in(case_dir("old_key")), Contains("libprt-basis-oldkey.so") &&
                                                  Contains("old build key") &&
                                                  Contains("\"gcc-4-foreign\""));
  CHECK_THAT(problem_in(case_dir("duplicate")),
             Contains("duplicate basis plug-in name \"constant\"") &&
                 Contains("libprt-basis-dup-a.so") && Contains("libprt-basis-dup-b.so"));
  CHECK_THAT(problem_in("/no/such/dir"), Contains("does not exist"));
  // A skipped file is an error only for a scene that names what it declares.
  PluginRegistry duplicate({case_dir("duplicate")});
  Params none;
  CHECK_THROWS_WITH(duplicate.create<Basis>("constant", none), Contains("duplicate"));
  PluginRegistry key({case_dir("build_key")});
  CHECK(key.names(PluginKind::basis).empty());
  CHECK_THROWS_WITH(key.find(PluginKind::basis, "key"), Contains("was built with align"));

  PluginRegistry throwing({case_dir("throwing")});
  Params p;
  CHECK_THROWS_WITH(throwing.create<Basis>("constant", p),
                    Contains("failed to construct: this test plug-in always fails"));
  PluginRegistry good({case_dir("good")});
  CHECK_THROWS_WITH(good.find(PluginKind::basis, "constnat"),
                    Contains("no basis plug-in named \"constnat\"; available: constant") &&
                        Contains("did you mean \"constant\""));
  CHECK_THROWS_WITH(good.find(PluginKind::renderer, "cpu"), Contains("available: (none found)"));
}

TEST_CASE("one bad file on the plug-in path does not hide the others", "[registry]") {
  PluginRegistry r({PRT_BUILD_PLUGIN_DIR, case_dir("not_a_plugin"), "/no/such/dir"});
  CHECK(r.problems().size() == 2);
  CHECK(r.names(PluginKind::basis) == std::vector<std::string>{"eigen", "haar", "hsh", "sg", "sh"});
  CHECK_NOTHROW(r.find(PluginKind::basis, "sh"));
  // A stale, unreadable copy named like a valid plug-in does not shadow it.
  const fs::path stale = fs::temp_directory_path() / "prt_registry_stale";
  fs::create_directories(stale);
  fs::permissions(stale, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                             fs::perms::others_read | fs::perms::others_exec);
  std::ofstream(stale / "libprt-basis-sh.so") << "not an ELF file";
  PluginRegistry with_stale({PRT_BUILD_PLUGIN_DIR, stale});
  CHECK(with_stale.problems().size() == 1);
  CHECK(with_stale.find(PluginKind::basis, "sh").file.parent_path() ==
        fs::path(PRT_BUILD_PLUGIN_DIR));
  fs::remove_all(stale);
}

TEST_CASE("PRT_PLUGIN_PATH adds directories after the build's", "[registry]") {
  const std::string path = case_dir("good").string() + ":" + case_dir("throwing").string();
  setenv("PRT_PLUGIN_PATH", path.c_str(), 1);
  const auto dirs = PluginRegistry::default_directories();
  unsetenv("PRT_PLUGIN_PATH");
  REQUIRE(dirs.size() == 3);
  CHECK(dirs[0] == fs::path(PRT_BUILD_PLUGIN_DIR));
  CHECK(dirs[1] == case_dir("good"));
  CHECK(dirs[2] == case_dir("throwing"));
}

TEST_CASE("the GPU renderer is asked for by capability, not by name", "[registry]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  // The scene's renderer when it draws on the GPU, else the first that does.
  CHECK(gpu_renderer(registry, "opengl") == "opengl");
  CHECK(gpu_renderer(registry, "cpu") == "opengl");
  CHECK(gpu_renderer(registry, "") == "opengl");
  // A plug-in folder with the CPU renderer alone has none: one message that
  // names what it found.
  const fs::path only_cpu =
      fs::temp_directory_path() / ("prt-gpu-renderer-test-" + std::to_string(::getpid()));
  fs::remove_all(only_cpu);
  fs::create_directories(only_cpu);
  fs::copy_file(fs::path(PRT_BUILD_PLUGIN_DIR) / "libprt-renderer-cpu.so",
                only_cpu / "libprt-renderer-cpu.so");
  PluginRegistry cpu_only({only_cpu});
  CHECK_THROWS_WITH(gpu_renderer(cpu_only, "cpu"),
                    Catch::Contains("no renderer plug-in draws on the GPU (found: cpu)"));
  fs::remove_all(only_cpu);
}
