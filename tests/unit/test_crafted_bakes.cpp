// Bake files crafted with a valid checksum (issue 44): the parse runs in a
// child process whose crash, endless loop or huge allocation is one message;
// the stream it sends back is checked frame by frame; the values and the
// plug-in records are checked against each other and the plug-ins' schemas.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <csignal>
#include <filesystem>
#include <thread>
#include <vector>

#include "../../framework/src/bake_stream.hpp"
#include "../../framework/src/bake_userblock.hpp"
#include "../../framework/src/child_process.hpp"
#include "../common/temp_files.hpp"
#include "prt/bake_checks.hpp"
#include "prt/bake_file.hpp"
#include "prt/error.hpp"
#include "prt/registry.hpp"

using namespace prt;
using Catch::Contains;
namespace fs = std::filesystem;

namespace {

fs::path fresh_dir(const std::string& name) {
  return test::fresh_dir("prt_crafted_", name);
}

// An sh order-2 bake of the box: 8 vertices x 4 coefficients, PCA with one
// component.
BakeData pca_bake() {
  BakeData d;
  d.scene_file = "scene.toml";
  d.basis = {"sh", "1.0.0", "order = 2\n"};
  d.compressor = {"pca", "1.0.0", "components = 1\n"};
  d.mesh = make_box();
  const auto vertices = static_cast<Eigen::Index>(d.mesh.vertex_count());
  d.transfer.coefficients = MatrixXfRow::Ones(vertices, 4);
  CompressedTransfer& c = d.compressed;
  c.compressor = "pca";
  c.dimension = 4;
  c.components = 1;
  c.cluster_of_vertex.assign(std::size_t(vertices), 0);
  c.weights = MatrixXfRow::Zero(vertices, 1);
  c.means = MatrixXfRow::Ones(1, 4);
  c.representatives = {MatrixXfRow::Zero(1, 4)};
  return d;
}

// What `send` writes (less than a pipe holds, so it never waits for the
// reader), read back as a bake by the receiver, or by `take`.
BakeData received(
    const std::function<void(int)>& send, double byte_limit = 1e6,
    const std::function<void(bake_stream::In&, BakeData&)>& take = [](auto& in, auto& data) {
      bake_stream::bake_fields(in, data);
    }) {
  int ends[2];
  REQUIRE(::pipe(ends) == 0);
  send(ends[1]);
  ::close(ends[1]);
  BakeData data;
  try {
    bake_stream::In in(ends[0], byte_limit, {}, data);
    take(in, data);
  } catch (...) {
    ::close(ends[0]);
    throw;
  }
  ::close(ends[0]);
  return data;
}

}  // namespace

TEST_CASE("a child that parses untrusted input cannot take the process down",
          "[hardening][crafted]") {
  const auto nothing = [](int fd) {
    char byte;
    while (::read(fd, &byte, 1) > 0) {
    }
    throw ChildStreamEnded();
  };
  CHECK_THROWS_WITH(
      exchange_with_child(
          "crash.h5", {}, [](int) { std::raise(SIGSEGV); }, nothing),
      Contains("crash.h5") && Contains("killed by signal 11") && Contains("nothing was read"));
  // An endless loop is stopped by the processor-time limit.
  const auto started = std::chrono::steady_clock::now();
  CHECK_THROWS_WITH(exchange_with_child(
                        "loop.h5", {0, 1},
                        [](int) {
                          for (volatile unsigned long i = 0;; i = i + 1) {
                          }
                        },
                        nothing),
                    Contains("loop.h5") && Contains("more than 1 s of processor time"));
  CHECK(std::chrono::steady_clock::now() - started < std::chrono::seconds(10));
  // An allocation beyond the memory limit fails in the child, not here (a
  // bad_alloc there, or a sanitizer's allocator that aborts the child).
  CHECK_THROWS_WITH(exchange_with_child(
                        "huge.h5", {64e6, 0},
                        [](int) {
                          std::vector<char> huge(std::size_t(4e9), 1);
                          ::_exit(huge[12345] == 1 ? 0 : 2);
                        },
                        nothing),
                    Contains("huge.h5") && Contains("nothing was read"));
  // A child that waits without using processor time is stopped by the idle limit.
  CHECK_THROWS_WITH(exchange_with_child(
                        "stuck.h5", {0, 0, 1},
                        [](int) {
                          for (;;) ::pause();
                        },
                        [](int fd) {
                          char byte;
                          read_from_child(fd, &byte, 1, 1);
                        }),
                    Contains("stuck.h5") && Contains("sent nothing for 1 s"));
  // The consumer's refusal ends the child and passes on unchanged.
  CHECK_THROWS_WITH(exchange_with_child(
                        "slow.h5", {},
                        [](int) {
                          for (;;) ::pause();
                        },
                        [](int) { throw Error("refused here"); }),
                    Contains("refused here"));
}

TEST_CASE("the bake stream is checked frame by frame before anything is allocated",
          "[hardening][crafted]") {
  BakeData good = pca_bake();
  const BakeData back = received([&](int fd) {
    bake_stream::Out out(fd);
    bake_stream::bake_fields(out, good);
  });
  CHECK(back.mesh.positions == good.mesh.positions);
  CHECK(back.transfer.coefficients == good.transfer.coefficients);
  CHECK(back.compressed.representatives.size() == 1);
  CHECK(back.compressor.parameters == good.compressor.parameters);

  // A stream cut short, a frame that claims more than the budget, a value
  // of another type, and the parse's own refusal.
  CHECK_THROWS_AS(received([&](int fd) { bake_stream::Out{fd}(std::string("scene.toml")); }),
                  ChildStreamEnded);
  CHECK_THROWS_WITH(received(
                        [&](int fd) {
                          bake_stream::Out out(fd);
                          bake_stream::bake_fields(out, good);
                        },
                        100),
                    Contains("more values than the file stores"));
  CHECK_THROWS_WITH(received([&](int fd) { bake_stream::Out{fd}(2.5); }),
                    Contains("a value of the wrong type"));
  CHECK_THROWS_WITH(received([&](int fd) { bake_stream::Out{fd}.fail("x.h5: bad bake file: y"); }),
                    Contains("x.h5: bad bake file: y"));
  // Every count of entries is bounded by the bytes that could follow it.
  CHECK_THROWS_WITH(received([&](int fd) { bake_stream::Out{fd}(1e15); }, 1e6,
                             [](bake_stream::In& in, BakeData& data) { in(data.metrics); }),
                    Contains("a bad count of values"));
}

TEST_CASE("crafted bakes that crashed the HDF5 library are one message", "[hardening][crafted]") {
  // Mutations that scripts/crafted_bakes.py found ending the parsing process
  // (libhdf5 1.10: SIGSEGV), each sealed with a valid checksum: in this
  // process they would have ended the test.
  const fs::path folder = fs::path(PRT_SOURCE_DIR) / "tests/fuzz/regressions/bake_sealed";
  int files = 0;
  for (const auto& entry : fs::directory_iterator(folder)) {
    ++files;
    CHECK_THROWS_WITH(read_bake(entry.path()), Contains(entry.path().filename().string()));
  }
  CHECK(files > 0);
}

TEST_CASE("an exact bake (a cluster per vertex) crosses the stream whole", "[hardening][crafted]") {
  // Thousands of empty representative blocks: their count is bounded by the
  // file's size, not by the bytes left after the arrays.
  const fs::path dir = fresh_dir("exact");
  BakeData exact = pca_bake();
  exact.mesh = make_sphere(4);
  exact.transfer.coefficients = MatrixXfRow::Random(Eigen::Index(exact.mesh.vertex_count()), 4);
  exact.compressed = exact_form(exact.transfer);
  exact.compressor = {"none", "1.0.0", ""};
  write_bake(dir / "exact.h5", exact);
  const BakeData back = read_bake(dir / "exact.h5");
  CHECK(back.compressed.clusters() == 2562);
  CHECK(back.compressed.representatives.size() == 2562);
  CHECK(back.compressed.means == exact.compressed.means);
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  CHECK(check_bake_records("exact.h5", back, registry).empty());
}

TEST_CASE("texts in a bake that are not text are refused, not printed", "[hardening][crafted]") {
  const fs::path dir = fresh_dir("texts");
  BakeData control = pca_bake();
  control.compressor.parameters = "components = 1\ninit = \"kmeans+\x0b\"\n";
  write_bake(dir / "control.h5", control);
  CHECK_THROWS_WITH(read_bake(dir / "control.h5"),
                    Contains("control.h5: bad bake file") &&
                        Contains("\"compressor_parameters\" holds a byte that is not text (0x0b"));
  BakeData utf8 = pca_bake();
  utf8.scene_file = "sc\xe9ne.toml";  // Latin-1, not UTF-8
  write_bake(dir / "latin1.h5", utf8);
  CHECK_THROWS_WITH(read_bake(dir / "latin1.h5"), Contains("\"scene_file\" holds a byte"));
  BakeData fine = pca_bake();
  fine.scene_file = "sc\xc3\xa8ne.toml";  // UTF-8
  write_bake(dir / "fine.h5", fine);
  CHECK(read_bake(dir / "fine.h5").scene_file == fine.scene_file);
}

TEST_CASE("a bake's plug-in records are checked against the plug-ins' schemas",
          "[hardening][crafted]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  CHECK(check_bake_records("good.h5", pca_bake(), registry).empty());

  BakeData order = pca_bake();
  order.basis.parameters = "order = 5000\n";
  CHECK_THROWS_WITH(check_bake_records("order.h5", order, registry),
                    Contains("order.h5: bad bake file") && Contains("order"));
  BakeData bigger = pca_bake();
  bigger.basis.parameters = "order = 3\n";
  CHECK_THROWS_WITH(check_bake_records("bigger.h5", bigger, registry),
                    Contains("4 columns") && Contains("9 coefficients"));
  BakeData budget = pca_bake();
  budget.compressor.parameters = "components = 0\n";
  CHECK_THROWS_WITH(check_bake_records("budget.h5", budget, registry),
                    Contains("1 components, more than components = 0"));
  BakeData unknown = pca_bake();
  unknown.compressor.parameters = "clusters = 3\n";
  CHECK_THROWS_WITH(check_bake_records("unknown.h5", unknown, registry), Contains("clusters"));
  BakeData exact = pca_bake();
  exact.compressor = {kExactRecord, "", ""};
  CHECK_THROWS_WITH(check_bake_records("exact.h5", exact, registry),
                    Contains("says its transfer is exact"));
  BakeData elsewhere = pca_bake();
  elsewhere.basis.name = "python_basis";
  CHECK(check_bake_records("elsewhere.h5", elsewhere, registry) ==
        std::vector<std::string>{"basis \"python_basis\""});
}
