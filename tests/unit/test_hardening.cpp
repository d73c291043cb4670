// Bad input is refused in bounded time and memory with one located message,
// and no output path can destroy data (issue: hardening).
#include <H5Cpp.h>
#include <elf.h>
#include <stb/stb_image_write.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "../../framework/src/bake_userblock.hpp"
#include "../common/temp_files.hpp"
#include "prt/bake_file.hpp"
#include "prt/environment.hpp"
#include "prt/error.hpp"
#include "prt/image.hpp"
#include "prt/mesh.hpp"
#include "prt/output_file.hpp"
#include "prt/registry.hpp"
#include "prt/scene.hpp"

using namespace prt;
using Catch::Contains;
namespace fs = std::filesystem;

namespace {

fs::path fresh_dir(const std::string& name) {
  return test::fresh_dir("prt_hardening_", name);
}

using test::read_file;
using test::write_file;

bool has_temporaries(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().find(".tmp-") != std::string::npos) return true;
  return false;
}

// Seconds a call takes; every refusal here must be far below a second.
template <class F>
double seconds_of(F&& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

BakeData small_bake() {
  BakeData d;
  d.scene_file = "scene.toml";
  d.scene_text = "[basis]\nplugin = \"sh\"\n";
  d.basis = {"sh", "1.0.0", "order = 2\n"};
  d.compressor = {"none", "1.0.0", ""};
  d.mesh = make_box();
  d.transfer.coefficients = MatrixXfRow::Ones(d.mesh.vertex_count(), 4);
  d.compressed.compressor = "none";
  d.compressed.dimension = 4;
  d.compressed.components = 0;
  d.compressed.cluster_of_vertex.assign(d.mesh.vertex_count(), 0);
  d.compressed.weights = MatrixXfRow(d.mesh.vertex_count(), 0);
  d.compressed.means = MatrixXfRow::Ones(1, 4);
  d.compressed.representatives = {MatrixXfRow(0, 4)};
  return d;
}

}  // namespace

TEST_CASE("outputs never replace inputs, devices, folders or files of another kind",
          "[hardening][output]") {
  const fs::path dir = fresh_dir("outputs");
  const fs::path scene = dir / "scene.toml", image = dir / "image.png", bake = dir / "bake.h5";
  write_file(scene, "[mesh]\ngenerate = \"box\"\n");
  const std::string scene_text = read_file(scene);
  write_bake(bake, small_bake());

  CHECK_THROWS_WITH(check_output({"/dev/null", FileKind::bake, "bake file"}, {}),
                    Contains("/dev/null") && Contains("character device"));
  CHECK_THROWS_WITH(check_output({dir, FileKind::bake, "bake file"}, {}), Contains("directory"));
  const fs::path fifo = dir / "fifo";
  REQUIRE(mkfifo(fifo.c_str(), 0600) == 0);
  CHECK_THROWS_WITH(check_output({fifo, FileKind::png, "image"}, {}), Contains("FIFO"));
  CHECK_THROWS_WITH(check_output({dir / "no" / "such" / "x.h5", FileKind::bake, "bake file"}, {}),
                    Contains("does not exist"));
  CHECK_NOTHROW(check_output({dir / "new_folder" / "x.h5", FileKind::bake, "bake file", true}, {}));
  // The same file as an input, by name, by another path, or by a hard link.
  CHECK_THROWS_WITH(check_output({scene, FileKind::bake, "bake file"}, {scene}, true),
                    Contains("same file as the input"));
  CHECK_THROWS_WITH(
      check_output({dir / "." / "bake.h5", FileKind::png, "image"}, {scene, bake}, true),
      Contains("same file as the input"));
  fs::create_hard_link(scene, dir / "link.toml");
  CHECK_THROWS_WITH(check_output({dir / "link.toml", FileKind::text, "table"}, {scene}, true),
                    Contains("same file"));
  // Another kind: refused unless forced; the same kind is replaced.
  Image pixel(1, 1);
  write_png(pixel, image, 1.0f);
  CHECK_THROWS_WITH(check_output({image, FileKind::bake, "bake file"}, {}),
                    Contains("refusing to replace a PNG image") && Contains("--force"));
  CHECK_THROWS_WITH(check_output({scene, FileKind::bake, "bake file"}, {}),
                    Contains("a scene file"));
  CHECK_THROWS_WITH(check_output({scene, FileKind::text, "table"}, {}),
                    Contains("refusing to replace a scene file"));
  const fs::path notes = dir / "notes.txt";
  write_file(notes, "notes\n");
  CHECK_NOTHROW(check_output({notes, FileKind::text, "table"}, {}));
  CHECK_NOTHROW(check_output({image, FileKind::bake, "bake file"}, {}, true));
  CHECK_NOTHROW(check_output({image, FileKind::png, "image"}, {}));
  CHECK_NOTHROW(check_output({bake, FileKind::bake, "bake file"}, {}));
  CHECK(read_file(scene) == scene_text);
  CHECK(detect_file_kind(bake) == FileKind::bake);
}

TEST_CASE("temporaries are exclusive, removed on error and SIGTERM, and stale ones cleaned",
          "[hardening][output]") {
  const fs::path dir = fresh_dir("temporaries");
  const fs::path file = dir / "out.txt";
  CHECK_THROWS(write_atomically(file, [](const fs::path&) { throw Error("boom"); }));
  CHECK_FALSE(has_temporaries(dir));
  CHECK_FALSE(fs::exists(file));

  // A process killed by SIGTERM while writing leaves nothing behind.
  const pid_t child = fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    write_atomically(file, [](const fs::path& temporary) {
      std::ofstream(temporary) << "partial";
      raise(SIGTERM);
    });
    _exit(0);
  }
  int status = 0;
  waitpid(child, &status, 0);
  CHECK(WIFSIGNALED(status));
  CHECK(WTERMSIG(status) == SIGTERM);
  CHECK_FALSE(has_temporaries(dir));
  CHECK_FALSE(fs::exists(file));

  // A temporary of a process that is gone (SIGKILL) is removed by the next write.
  const pid_t dead = fork();
  if (dead == 0) _exit(0);
  waitpid(dead, &status, 0);
  const fs::path stale = dir / (".out.txt.tmp-" + std::to_string(dead) + "-0");
  write_file(stale, "left by a killed run");
  write_text_file(file, "complete\n");
  CHECK_FALSE(fs::exists(stale));
  CHECK(read_file(file) == "complete\n");
  CHECK_FALSE(has_temporaries(dir));
}

TEST_CASE("a damaged, truncated or crafted bake file is refused before it is parsed",
          "[hardening][bake]") {
  const fs::path dir = fresh_dir("bakes");
  const fs::path good = dir / "good.h5";
  write_bake(good, small_bake());
  REQUIRE_NOTHROW(read_bake(good));
  CHECK(read_file(good).rfind("PRT-BAKE\n", 0) == 0);

  // Any flipped bit after the header is caught by the checksum.
  std::string bytes = read_file(good);
  for (std::size_t at : {std::size_t(600), bytes.size() / 2, bytes.size() - 10}) {
    std::string flipped = bytes;
    flipped[at] ^= 0x10;
    write_file(dir / "flipped.h5", flipped);
    CHECK_THROWS_WITH(read_bake(dir / "flipped.h5"),
                      Contains("flipped.h5") && Contains("checksum mismatch"));
  }
  write_file(dir / "cut.h5", bytes.substr(0, bytes.size() * 2 / 3));
  double seconds = seconds_of([&] {
    CHECK_THROWS_WITH(read_bake(dir / "cut.h5"), Contains("cut.h5") && Contains("truncated"));
  });
  CHECK(seconds < 1.0);

  // Crafted files with a valid checksum: external links and storage are refused.
  fs::copy_file(good, dir / "link.h5");
  {
    H5::H5File f((dir / "link.h5").string(), H5F_ACC_RDWR);
    H5Lcreate_external("/etc/passwd", "/", f.openGroup("mesh").getId(), "outside", H5P_DEFAULT,
                       H5P_DEFAULT);
  }
  seal_bake_file(dir / "link.h5", kBakeFormatVersion);
  CHECK_THROWS_WITH(read_bake(dir / "link.h5"), Contains("external link"));

  fs::copy_file(good, dir / "external.h5");
  {
    H5::H5File f((dir / "external.h5").string(), H5F_ACC_RDWR);
    H5::DSetCreatPropList properties;
    H5Pset_external(properties.getId(), "/etc/passwd", 0, 64);
    const hsize_t dims[2] = {8, 1};
    f.openGroup("basis_state")
        .createDataSet("stolen", H5::PredType::NATIVE_DOUBLE, H5::DataSpace(2, dims), properties);
  }
  seal_bake_file(dir / "external.h5", kBakeFormatVersion);
  CHECK_THROWS_WITH(read_bake(dir / "external.h5"), Contains("external storage"));

  // A dataset that declares more values than the file holds is refused
  // before anything is allocated for it.
  fs::copy_file(good, dir / "huge.h5");
  {
    H5::H5File f((dir / "huge.h5").string(), H5F_ACC_RDWR);
    const hsize_t dims[2] = {200000000, 3}, chunk[2] = {4096, 3};
    H5::DSetCreatPropList properties;
    properties.setChunk(2, chunk);
    f.openGroup("basis_state")
        .createDataSet("unallocated", H5::PredType::NATIVE_DOUBLE, H5::DataSpace(2, dims),
                       properties);
  }
  seal_bake_file(dir / "huge.h5", kBakeFormatVersion);
  seconds = seconds_of([&] {
    CHECK_THROWS_WITH(read_bake(dir / "huge.h5"),
                      Contains("unallocated") && Contains("not stored in the file"));
  });
  CHECK(seconds < 1.0);
}

TEST_CASE("values in a bake file are validated", "[hardening][bake]") {
  const fs::path dir = fresh_dir("values");
  BakeData nan = small_bake();
  nan.compressed.means(0, 1) = std::nanf("");
  CHECK_THROWS_WITH(write_bake(dir / "nan.h5", nan), Contains("NaN"));
  CHECK_FALSE(fs::exists(dir / "nan.h5"));

  BakeData super = small_bake();
  super.compressed.supercluster_of_cluster = {1000000000};
  CHECK_THROWS_WITH(write_bake(dir / "super.h5", super), Contains("supercluster id"));

  // A crafted file whose transfer columns disagree with the compressed dimension.
  write_bake(dir / "columns.h5", small_bake());
  {
    H5::H5File f((dir / "columns.h5").string(), H5F_ACC_RDWR);
    double dimension = 5;
    f.openGroup("compressed")
        .openAttribute("dimension")
        .write(H5::PredType::NATIVE_DOUBLE, &dimension);
  }
  seal_bake_file(dir / "columns.h5", kBakeFormatVersion);
  CHECK_THROWS_WITH(read_bake(dir / "columns.h5"), Contains("compressed dimension is 5"));

  // Scene text of any size is stored.
  BakeData large = small_bake();
  large.scene_text = std::string(200000, '#');
  write_bake(dir / "large.h5", large);
  CHECK(read_bake(dir / "large.h5").scene_text == large.scene_text);
}

TEST_CASE("mesh headers that declare more than the file holds are refused at once",
          "[hardening][mesh]") {
  const fs::path dir = fresh_dir("meshes");
  const std::vector<std::pair<std::string, std::string>> cases{
      {"huge_vertices.off", "OFF\n1000000000000 1 0\n0 0 0\n"},
      {"huge_faces.off", "OFF\n3 1000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
      {"no_end_header.ply", "ply\nformat ascii 1.0\nelement vertex 100000000\n"},
      // Found by fuzz.smoke: an index beyond an int put OpenMesh's OFF reader
      // in a loop that grew to 8 GB.
      {"index_beyond_int.off",
       "OFF\n4 2 0\n0 0 0\n2 0 0\n0 1 0\n0 0 1\n3 1 1111111111111111111 0 1 4\n3 0 1 2\n"},
      {"binary_short.ply",
       "ply\nformat binary_little_endian 1.0\nelement vertex 90000000\nproperty float x\n"
       "property float y\nproperty float z\nend_header\n"},
      {"short.stl", std::string(80, ' ') + std::string("\xff\xff\xff\x0f", 4) + "abc"},
  };
  for (const auto& [name, text] : cases) {
    write_file(dir / name, text);
    const double seconds =
        seconds_of([&, n = name] { CHECK_THROWS_WITH(load_mesh(dir / n), Contains(n)); });
    CHECK(seconds < 1.0);
  }
  CHECK_THROWS_WITH(load_mesh(dir / "huge_vertices.off"), Contains("1000000000000"));
  CHECK_THROWS_WITH(load_mesh(dir / "no_end_header.ply"), Contains("end_header"));
  CHECK_THROWS_WITH(load_mesh(dir / "index_beyond_int.off"),
                    Contains("vertex index \"1111111111111111111\"") && Contains("4 vertices"));
  CHECK_THROWS_WITH(load_mesh(dir), Contains("directory"));
  CHECK_THROWS_WITH(load_mesh("/dev/zero"), Contains("not a regular file"));
}

TEST_CASE("truncated meshes and bad face indices are refused, not dropped", "[hardening][mesh]") {
  const fs::path dir = fresh_dir("truncated");
  // A sphere as ASCII OFF, cut at 60%.
  const Mesh sphere = make_sphere(2);
  std::string off = "OFF\n" + std::to_string(sphere.vertex_count()) + " " +
                    std::to_string(sphere.triangles.size()) + " 0\n";
  for (const auto& p : sphere.positions)
    off += std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
  for (const auto& t : sphere.triangles)
    off += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) +
           "\n";
  write_file(dir / "whole.off", off);
  CHECK(load_mesh(dir / "whole.off").triangles.size() == sphere.triangles.size());
  write_file(dir / "cut.off", off.substr(0, off.size() * 6 / 10));
  CHECK_THROWS_WITH(load_mesh(dir / "cut.off"), Contains("cut.off") && Contains("truncated"));

  // Binary PLY faces with indices 999999 and -5.
  auto binary_ply = [](std::int32_t bad) {
    std::string ply =
        "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n"
        "property float y\nproperty float z\nelement face 2\n"
        "property list uchar int vertex_indices\nend_header\n";
    const float positions[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    ply.append(reinterpret_cast<const char*>(positions), sizeof positions);
    for (const std::array<std::int32_t, 3>& face :
         {std::array<std::int32_t, 3>{0, 1, 2}, std::array<std::int32_t, 3>{0, 2, bad}}) {
      ply.push_back(3);
      ply.append(reinterpret_cast<const char*>(face.data()), 12);
    }
    return ply;
  };
  write_file(dir / "good.ply", binary_ply(3));
  CHECK(load_mesh(dir / "good.ply").triangles.size() == 2);
  for (std::int32_t bad : {999999, -5}) {
    write_file(dir / "bad.ply", binary_ply(bad));
    CHECK_THROWS_WITH(load_mesh(dir / "bad.ply"), Contains("bad.ply") && Contains("face"));
  }

  // An ASCII STL that stops after two of its facets.
  std::string stl = "solid s\n";
  for (int f = 0; f < 4; ++f)
    stl += "facet normal 0 0 1\nouter loop\nvertex " + std::to_string(f) + " 0 0\nvertex " +
           std::to_string(f + 1) + " 0 0\nvertex " + std::to_string(f) +
           " 1 0\nendloop\nendfacet\n";
  write_file(dir / "whole.stl", stl + "endsolid s\n");
  CHECK(load_mesh(dir / "whole.stl").triangles.size() == 4);
  write_file(dir / "cut.stl", stl.substr(0, stl.size() / 2));
  CHECK_THROWS_WITH(load_mesh(dir / "cut.stl"), Contains("cut.stl") && Contains("truncated"));
}

TEST_CASE("Radiance images with missing pixels or of another format are refused",
          "[hardening][image]") {
  const fs::path dir = fresh_dir("images");
  // A real run-length-encoded .hdr, written by stb (whose implementation libprt holds).
  const int width = 64, height = 32;
  std::vector<float> rgb(std::size_t(3) * width * height);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = 0.1f + float(i % 97) / 97.f;
  REQUIRE(stbi_write_hdr((dir / "good.hdr").c_str(), width, height, 3, rgb.data()));
  CHECK(Environment::load(dir / "good.hdr").width() == width);
  const std::string bytes = read_file(dir / "good.hdr");
  write_file(dir / "cut.hdr", bytes.substr(0, bytes.size() - 200));
  CHECK_THROWS_WITH(Environment::load(dir / "cut.hdr"),
                    Contains("cut.hdr") && Contains("truncated"));
  write_png(Image(2, 2), dir / "image.png", 1.0f);
  fs::copy_file(dir / "image.png", dir / "renamed.hdr");
  CHECK_THROWS_WITH(Environment::load(dir / "renamed.hdr"),
                    Contains("renamed.hdr") && Contains("not a Radiance HDR image"));
  write_file(dir / "huge.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 900000 +X 900000\n");
  CHECK_THROWS_WITH(Environment::load(dir / "huge.hdr"), Contains("huge.hdr"));
}

TEST_CASE("scene files: not a file, not UTF-8 text, degenerate camera", "[hardening][scene]") {
  PluginRegistry registry({PRT_BUILD_PLUGIN_DIR});
  const fs::path dir = fresh_dir("scenes");
  CHECK_THROWS_WITH(SceneSpec::load(dir, registry), Contains("directory"));
  write_file(dir / "binary.toml", std::string("[mesh]\ngenerate = \"box\xff\xfe\"\n"));
  CHECK_THROWS_WITH(SceneSpec::load(dir / "binary.toml", registry),
                    Contains("binary.toml:2:") && Contains("UTF-8"));
  write_file(dir / "nul.toml", std::string("[mesh]\0\n", 8));
  CHECK_THROWS_WITH(SceneSpec::load(dir / "nul.toml", registry),
                    Contains("nul.toml:1:7") && Contains("control character"));
  // toml++ reaches undefined behaviour on non-ASCII text where a token may
  // start; inside strings and comments it is fine.
  write_file(dir / "bare.toml", "[mesh]\ngenerate = \xc3\xa9\n");
  CHECK_THROWS_WITH(SceneSpec::load(dir / "bare.toml", registry),
                    Contains("bare.toml:2:12") && Contains("non-ASCII character outside"));
  write_file(dir / "accents.toml",
             "# caf\xc3\xa9 \xef\xb3\xbf\n[mesh]\ngenerate = \"box\" # \xc3\xa9\n[lighting]\n"
             "constant = [1, 1, 1]\n[output]\nimage = 'caf\xc3\xa9.png'\n");
  CHECK(SceneSpec::load(dir / "accents.toml", registry).image_path().filename() ==
        "caf\xc3\xa9.png");
  // A section-level error still has a line and column.
  write_file(dir / "nomesh.toml", "[lighting]\nconstant = [1, 1, 1]\n");
  CHECK_THROWS_WITH(SceneSpec::load(dir / "nomesh.toml", registry),
                    Contains("nomesh.toml:1:1: error"));
  write_file(dir / "camera.toml",
             "[mesh]\ngenerate = \"box\"\n[lighting]\nconstant = [1, 1, 1]\n[camera]\n"
             "position = [1, 2, 3]\ntarget = [1, 2, 3]\n");
  const SceneSpec scene = SceneSpec::load(dir / "camera.toml", registry);
  CHECK_THROWS_WITH(scene.make_camera(scene.load_mesh()),
                    Contains("camera.toml:6:") && Contains("coincide"));
}

TEST_CASE("the plug-in scanner reads headers only and skips unsafe or damaged files",
          "[hardening][registry]") {
  const fs::path dir = fresh_dir("plugins");
  fs::permissions(dir, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                           fs::perms::others_read | fs::perms::others_exec);
  const fs::path good = fs::path(PRT_TEST_PLUGIN_DIR) / "good" / "libprt-basis-good.so";
  fs::copy_file(good, dir / "libprt-basis-good.so");

  // .dynstr claiming to run past the file's end: no out-of-bounds read.
  std::string elf = read_file(good);
  Elf64_Ehdr header;
  std::memcpy(&header, elf.data(), sizeof header);
  for (int i = 0; i < header.e_shnum; ++i) {
    Elf64_Shdr section;
    const std::size_t at = header.e_shoff + i * sizeof section;
    std::memcpy(&section, elf.data() + at, sizeof section);
    if (section.sh_type == SHT_STRTAB) section.sh_size = elf.size() * 4;
    std::memcpy(elf.data() + at, &section, sizeof section);
  }
  write_file(dir / "libprt-basis-strtab.so", elf);
  // A 1 GiB file costs no more than its header to inspect.
  {
    std::ofstream junk(dir / "libprt-basis-junk.so", std::ios::binary);
    junk << "\x7f"
            "ELF junk";
  }
  fs::resize_file(dir / "libprt-basis-junk.so", std::uintmax_t(1) << 30);
  const double seconds = seconds_of([&] {
    PluginRegistry r({dir});
    CHECK(r.names(PluginKind::basis) == std::vector<std::string>{"constant"});
    CHECK(r.problems().size() == 2);
  });
  CHECK(seconds < 1.0);
  fs::remove(dir / "libprt-basis-junk.so");

  // Writable by others: the folder, or a file in it, is skipped with a reason.
  fs::permissions(dir / "libprt-basis-good.so", fs::perms::others_write, fs::perm_options::add);
  {
    PluginRegistry r({dir});
    CHECK(r.names(PluginKind::basis).empty());
    CHECK_THROWS_WITH(r.find(PluginKind::basis, "good"), Contains("writable by others"));
  }
  fs::permissions(dir / "libprt-basis-good.so", fs::perms::others_write, fs::perm_options::remove);
  fs::permissions(dir, fs::perms::group_write, fs::perm_options::add);
  PluginRegistry r({dir});
  CHECK(r.names(PluginKind::basis).empty());
  REQUIRE_FALSE(r.problems().empty());
  CHECK_THAT(r.problems()[0].message, Contains("writable by others"));
}
