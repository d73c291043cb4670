// Issue 45: writes checked end to end, side files of meshes not followed,
// plug-in folders judged with their ancestors, located messages for the
// inputs that used to be accepted silently.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <sys/stat.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "../common/temp_files.hpp"
#include "prt/environment.hpp"
#include "prt/error.hpp"
#include "prt/image.hpp"
#include "prt/log.hpp"
#include "prt/mesh.hpp"
#include "prt/output_file.hpp"
#include "prt/registry.hpp"

using namespace prt;
using Catch::Matchers::Contains;
namespace fs = std::filesystem;

namespace {

fs::path fresh_dir(const std::string& name) {
  return test::fresh_dir("prt_reliability_", name);
}

using test::read_file;
using test::write_file;

// A float EXR with the named channels, every value `value`.
void write_exr(const fs::path& file, const std::vector<std::string>& channels, float value,
               int width = 4, int height = 2) {
  Imf::Header header(width, height);
  for (const auto& c : channels) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
  std::vector<float> pixels(std::size_t(width) * height, value);
  Imf::FrameBuffer buffer;
  for (const auto& c : channels)
    buffer.insert(c, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(pixels.data()), sizeof(float),
                                sizeof(float) * width));
  Imf::OutputFile out(file.c_str(), header);
  out.setFrameBuffer(buffer);
  out.writePixels(height);
}

}  // namespace

TEST_CASE("a failed write is one located message and replaces nothing", "[reliability]") {
  // /dev/full fails every write with ENOSPC, as a full disk does.
  CHECK_THROWS_WITH(write_bytes_checked("/dev/full", "abc", 3, "out/x.png"),
                    "out/x.png: no space left on device while writing");
  CHECK(io_failure("a/b.h5", ENOSPC, "writing") == "a/b.h5: no space left on device while writing");

  // A writer that fails leaves the old file and no temporary.
  const fs::path dir = fresh_dir("atomic");
  write_file(dir / "old.txt", "keep me\n");
  CHECK_THROWS_WITH(write_atomically(dir / "old.txt",
                                     [&](const fs::path&) {
                                       write_bytes_checked("/dev/full", "x", 1, dir / "old.txt");
                                     }),
                    Contains("no space left on device while writing"));
  CHECK(read_file(dir / "old.txt") == "keep me\n");
  CHECK(std::distance(fs::directory_iterator(dir), fs::directory_iterator()) == 1);

  // Text files go through the same checked writes.
  write_text_file(dir / "new.txt", "hello\n");
  CHECK(read_file(dir / "new.txt") == "hello\n");
}

TEST_CASE("PNGs of no pixels or a non-finite exposure are refused", "[reliability]") {
  const fs::path dir = fresh_dir("png");
  Image empty;
  CHECK_THROWS_WITH(write_png(empty, dir / "a.png", 1.f), Contains("0 x 0 pixels"));
  Image one(1, 1);
  one.rgb = {0.5f, 0.5f, 0.5f};
  CHECK_THROWS_WITH(write_png(one, dir / "a.png", std::nanf("")), Contains("exposure"));
  CHECK_FALSE(fs::exists(dir / "a.png"));
  write_png(one, dir / "a.png", 1.f);
  const Image8 back = read_png(dir / "a.png");
  CHECK(back.width == 1);
  CHECK(back.height == 1);
}

TEST_CASE("report files replace reports, not notes", "[reliability]") {
  const fs::path dir = fresh_dir("reports");
  write_file(dir / "notes.txt", "my notes\n");
  write_file(dir / "old.json", "{\"a\": 1}\n");
  write_file(dir / "table.csv", "a,b\n1,2\n");
  CHECK(detect_file_kind(dir / "notes.txt") == FileKind::text);
  CHECK(detect_file_kind(dir / "old.json") == FileKind::json);
  CHECK(detect_file_kind(dir / "table.csv") == FileKind::csv);
  CHECK_THROWS_WITH(check_output({dir / "notes.txt", FileKind::json, "report"}, {}),
                    Contains("refusing to replace a text file with a JSON file"));
  CHECK_NOTHROW(check_output({dir / "notes.txt", FileKind::json, "report"}, {}, true));
  CHECK_NOTHROW(check_output({dir / "old.json", FileKind::json, "report"}, {}));
  CHECK_NOTHROW(check_output({dir / "table.csv", report_kind(dir / "table.csv"), "table"}, {}));
}

TEST_CASE("long values are elided in messages, filesystem errors name their path",
          "[reliability]") {
  const std::string key(1000000, 'k');
  const Error e("scene.toml:3:1: error: unknown parameter \"" + key + "\"");
  CHECK(std::string(e.what()).size() < Error::kMaxMessage + 64);
  CHECK_THAT(e.what(), Contains("characters elided"));
  CHECK_THAT(e.what(), Contains("scene.toml:3:1"));
  CHECK(elide("short") == "short");
  CHECK(elide(std::string(200, 'x'), 80).size() < 120);
  const std::filesystem::filesystem_error fs_error(
      "cannot create directories", "/ro/folder",
      std::make_error_code(std::errc::read_only_file_system));
  CHECK_THAT(filesystem_message(fs_error),
             Catch::StartsWith("/ro/folder: cannot create directories"));
}

TEST_CASE("an OBJ's material libraries are not followed: FIFOs, devices, outside paths",
          "[reliability][mesh]") {
  const fs::path dir = fresh_dir("mtllib");
  REQUIRE(mkfifo((dir / "fifo.mtl").c_str(), 0644) == 0);
  fs::create_symlink("/dev/urandom", dir / "urandom.mtl");
  const std::string triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  for (const std::string library : {"fifo.mtl", "urandom.mtl", "../../../../../../dev/zero"}) {
    write_file(dir / "mesh.obj", "mtllib " + library + "\nusemtl red\n" + triangle);
    const auto start = std::chrono::steady_clock::now();
    const Mesh mesh = load_mesh(dir / "mesh.obj");  // a hang here is the defect
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    CHECK(seconds < 1.0);
    CHECK(mesh.vertex_count() == 3);
    CHECK(mesh.triangles.size() == 1);
  }
}

TEST_CASE("STL facets of other than three corners are refused", "[reliability][mesh]") {
  const fs::path dir = fresh_dir("stl");
  write_file(dir / "quad.stl",
             "solid q\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\n"
             "vertex 0 1 0\nendloop\nendfacet\nendsolid q\n");
  CHECK_THROWS_WITH(load_mesh(dir / "quad.stl"), Contains("facet 1 has 4 vertices"));
}

TEST_CASE("environment maps: damaged magnitudes, missing channels, negative values",
          "[reliability][environment]") {
  const fs::path dir = fresh_dir("maps");
  // An RGBE pixel of exponent 255 decodes to ~1.7e38: damage, not light.
  std::string hdr = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 2\n";
  hdr += std::string("\x80\x80\x80\xff\x80\x80\x80\x80", 8);
  write_file(dir / "exponent.hdr", hdr);
  CHECK_THROWS_WITH(Environment::load(dir / "exponent.hdr"),
                    Contains("pixel (0, 0) holds") && Contains("RGBE exponent of 255"));

  // Finite floats beyond half's range are named as what they are.
  write_exr(dir / "huge.exr", {"R", "G", "B"}, 3e38f);
  CHECK_THROWS_WITH(Environment::load(dir / "huge.exr"),
                    Contains("pixel (0, 0) holds 3e+38") && !Contains("infinite"));
  write_exr(dir / "gb.exr", {"G", "B"}, 1.f);
  CHECK_THROWS_WITH(Environment::load(dir / "gb.exr"),
                    Contains("no R channel") && Contains("it has B, G"));
  write_exr(dir / "grey.exr", {"Y"}, 2.f);
  CHECK(Environment::load(dir / "grey.exr").pixels() == std::vector<float>(4 * 2 * 3, 2.f));
  write_exr(dir / "negative.exr", {"R", "G", "B"}, -0.5f);
  // Clamped to 0, with a warning that does not divide by the zero energy
  // left (it said "1.2e+303% of the map's energy").
  std::string warning;
  set_log_sink([&](LogLevel, const std::string& text) { warning += text; });
  CHECK(Environment::load(dir / "negative.exr").pixels() == std::vector<float>(4 * 2 * 3, 0.f));
  set_log_sink(nullptr);
  CHECK_THAT(warning, Contains("24 negative value(s), no positive value in the map"));
  write_exr(dir / "fine.exr", {"R", "G", "B"}, 1.5f);
  CHECK(Environment::load(dir / "fine.exr").pixels() == std::vector<float>(4 * 2 * 3, 1.5f));
}

TEST_CASE("a plug-in folder below a folder others may write is skipped",
          "[reliability][registry]") {
  const fs::path parent = fresh_dir("plugin_parent");
  const fs::path folder = parent / "inner" / "plugins";
  fs::create_directories(folder);
  for (const fs::path& p : {parent / "inner", folder})
    fs::permissions(p, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                           fs::perms::others_read | fs::perms::others_exec);
  fs::copy_file(fs::path(PRT_TEST_PLUGIN_DIR) / "good" / "libprt-basis-good.so",
                folder / "libprt-basis-good.so");
  {
    PluginRegistry safe({folder});
    CHECK(safe.names(PluginKind::basis) == std::vector<std::string>{"constant"});
  }
  // A grandparent others may write (no sticky bit): skipped, naming it.
  fs::permissions(parent, fs::perms::all);
  {
    PluginRegistry r({folder});
    CHECK(r.names(PluginKind::basis).empty());
    REQUIRE_FALSE(r.problems().empty());
    CHECK_THAT(r.problems()[0].message,
               Contains("parent " + parent.string() + " is writable by others"));
  }
  // Reached through a symlink that lies in such a folder: skipped too.
  fs::permissions(parent, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                              fs::perms::others_read | fs::perms::others_exec);
  const fs::path open_folder = fresh_dir("plugin_open");
  fs::permissions(open_folder, fs::perms::all);
  fs::create_directory_symlink(folder, open_folder / "link");
  {
    PluginRegistry r({open_folder / "link"});
    CHECK(r.names(PluginKind::basis).empty());
  }
  // A sticky world-writable folder (as /tmp) is fine: only an entry's owner may replace it.
  fs::permissions(parent, fs::perms::all | fs::perms::sticky_bit);
  {
    PluginRegistry r({folder});
    CHECK(r.names(PluginKind::basis) == std::vector<std::string>{"constant"});
  }
  fs::permissions(parent, fs::perms::owner_all);
}
