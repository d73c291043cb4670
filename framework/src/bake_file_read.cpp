// The bake file's reader: the seal (length, CRC) first, so a damaged file
// never reaches libhdf5's parser; then a child process parses the file
// (libhdf5 cannot take this process down) and sends its fields, which are
// checked here again, each with its size, type and range, and against each
// other (bake_values.cpp); any failure names the file and what was read.
#include <H5Cpp.h>

#include "bake_hdf5.hpp"
#include "bake_stream.hpp"
#include "bake_userblock.hpp"
#include "bake_values.hpp"
#include "child_process.hpp"
#include "prt/bake_file.hpp"
#include "prt/error.hpp"

namespace prt {
namespace fs = std::filesystem;
using namespace bake_hdf5;

namespace {

// The parse's bounds: memory beyond twice the file (its values, once read,
// and libhdf5's caches) and processor time (a 300 MB bake parses in about a
// second; an endless loop is stopped).
constexpr double kParseMemory = 512e6, kParseSeconds = 10, kParseBytesPerSecond = 20e6;

// The root's attributes: format, scene, plug-ins, albedo.
// `version`: the sealed header's, which the attribute must repeat.
void read_header(const H5::H5File& h5, BakeData& data, int version) {
  H5::Group root = open_group(h5, "/");
  if (!root.attrExists("format") || read_text(root, "format") != kFormatName)
    throw Error("it is an HDF5 file but not a PRT bake");
  if (read_number(root, "format_version") != version)
    throw Error("its header and its format_version attribute disagree");
  // Version 5 says the rows are at receivers (/receivers); 4 at the vertices.
  data.receivers.kind = "vertices";  // version 5: /receivers says which (read_receivers)
  data.scene_file = read_text(root, "scene_file");
  data.scene_text = read_bytes(root, "scene_text");
  data.transport = read_text(root, "transport");
  data.basis = read_plugin(root, "basis");
  data.compressor = read_plugin(root, "compressor");
  for (int c = 0; c < 3; ++c)
    data.albedo[c] = static_cast<float>(read_number(root, "albedo_" + std::string(1, "rgb"[c])));
}

void read_mesh(const H5::H5File& h5, BakeData& data) {
  H5::Group mesh = open_group(h5, "mesh");
  data.mesh.positions = read_vectors<Eigen::Vector3f, float>(mesh, "positions");
  data.mesh.normals = read_vectors<Eigen::Vector3f, float>(mesh, "normals");
  data.mesh.triangles =
      read_vectors<std::array<std::uint32_t, 3>, std::uint32_t>(mesh, "triangles");
  if (mesh.nameExists("uvs")) data.mesh.uvs = read_vectors<Eigen::Vector2f, float>(mesh, "uvs");
}

// The texels of a version 5 file and their points (checked in bake_values.cpp).
void read_texels(const H5::Group& receivers, BakeData& data) {
  TexelAtlas& atlas = data.receivers.atlas;
  atlas.width = int(read_count(receivers, "width", 16384));
  atlas.height = int(read_count(receivers, "height", 16384));
  hsize_t rows, cols;
  atlas.texels = read_array<std::uint32_t>(receivers, "texels", rows, cols);
  data.receivers.points.positions = read_vectors<Eigen::Vector3f, float>(receivers, "positions");
  data.receivers.points.normals = read_vectors<Eigen::Vector3f, float>(receivers, "normals");
}

// The probe grid of a version 5 file (checked in bake_values.cpp).
void read_receivers(const H5::H5File& h5, BakeData& data, int version) {
  if (version != kReceiversFormatVersion) return;
  H5::Group receivers = open_group(h5, "receivers");
  data.receivers.kind = read_text(receivers, "kind");
  if (data.receivers.texels()) return read_texels(receivers, data);
  if (!data.receivers.probes())
    throw Error("/receivers names a kind of receiver other than texels or probes");
  ProbeGrid& grid = data.receivers.grid;
  grid.spacing = float(read_number(receivers, "spacing"));
  for (int a = 0; a < 3; ++a) {
    const std::string axis(1, "xyz"[a]);
    grid.origin[a] = float(read_number(receivers, "origin_" + axis));
    const double count = read_number(receivers, "count_" + axis);
    if (!(count >= 1 && count <= 4096)) throw Error("/receivers count_" + axis + " out of range");
    grid.counts[std::size_t(a)] = int(count);
  }
  hsize_t rows, cols;
  data.receivers.valid = read_array<std::uint8_t>(receivers, "valid", rows, cols);
}

// Colour materials: how many channel transfers, and which one each colour
// channel reads (absent: one transfer). Checked in bake_values.cpp.
void read_channel_groups(const H5::Group& transfer, TransferSignal& signal) {
  if (!transfer.attrExists("channel_groups")) return;
  signal.channel_groups = static_cast<int>(read_count(transfer, "channel_groups", 3));
  for (int c = 0; c < 3; ++c)
    signal.group_of_channel[std::size_t(c)] =
        static_cast<int>(read_count(transfer, std::string("group_of_channel_") + "rgb"[c], 2));
}

// The transfer's layout; its rows, and those of its direct part, are read
// a block at a time as they are sent (bake_stream::Out::rows).
void read_transfer(const H5::H5File& h5, BakeData& data, bake_stream::Out& out) {
  const H5::Group root = open_group(h5, "/");
  H5::Group transfer = open_group(h5, "transfer");
  data.transfer.kind = read_text(transfer, "kind");
  data.material = read_text(transfer, "material");
  data.bounces = static_cast<int>(read_count(transfer, "bounces", 1000));
  data.subsurface = read_count(transfer, "subsurface", 1) != 0;
  data.transfer.exit_rows = static_cast<int>(read_count(transfer, "exit_rows", 1 << 20));
  if (data.transfer.glossy() || data.receivers.probes())
    data.exit = read_plugin(root, "exit_basis");
  read_channel_groups(transfer, data.transfer);
  out.transfer_rows = dataset_rows(transfer, "coefficients");
  if (data.bounces > 0 && transfer.nameExists("direct_coefficients"))
    out.direct_rows = dataset_rows(transfer, "direct_coefficients");
}

void read_compressed(const H5::H5File& h5, BakeData& data) {
  hsize_t rows, cols;
  H5::Group compressed = open_group(h5, "compressed");
  CompressedTransfer& c = data.compressed;
  c.compressor = read_text(compressed, "compressor");
  c.components = static_cast<int>(read_count(compressed, "components", 1 << 30));
  c.dimension = static_cast<Eigen::Index>(read_count(compressed, "dimension", 1 << 30));
  c.cluster_of_vertex = read_array<std::int32_t>(compressed, "cluster_of_vertex", rows, cols);
  c.weights = read_matrix(compressed, "weights");
  c.means = read_matrix(compressed, "means");
  const MatrixXfRow stacked = read_matrix(compressed, "representatives");
  const auto counts = read_array<std::int32_t>(compressed, "components_of_cluster", rows, cols);
  c.supercluster_of_cluster =
      read_array<std::int32_t>(compressed, "supercluster_of_cluster", rows, cols);
  c.weight_index = read_array<std::int32_t>(compressed, "weight_index", rows, cols);
  Eigen::Index total = 0;
  for (auto n : counts) {
    if (n < 0) throw Error("a cluster has " + std::to_string(n) + " components");
    total += n;
  }
  if (static_cast<Eigen::Index>(counts.size()) != c.clusters() || total != stacked.rows())
    throw Error("compressed transfer has inconsistent sizes");
  for (Eigen::Index k = 0, row = 0; k < c.clusters(); row += counts[k++]) {
    if (counts[k] < 0 || counts[k] > c.components)
      throw Error("cluster " + std::to_string(k) + " has " + std::to_string(counts[k]) +
                  " components, outside [0, " + std::to_string(c.components) + "]");
    c.representatives.push_back(stacked.middleRows(row, counts[k]));
  }
}

// The bases' fitted states and the bake's metrics.
void read_states_and_metrics(const H5::H5File& h5, BakeData& data) {
  hsize_t rows, cols;
  for (const auto& [group, basis_state] :
       {std::pair{"basis_state", &data.basis_state}, {"exit_state", &data.exit_state}}) {
    H5::Group state = open_group(h5, group);
    for (hsize_t i = 0; i < state.getNumObjs(); ++i) {
      const std::string name = state.getObjnameByIdx(i);
      auto values = read_array<double>(state, name, rows, cols);
      basis_state->matrices[name] =
          Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
              values.data(), rows, cols);
    }
  }
  H5::Group metrics = open_group(h5, "metrics");
  for (int i = 0; i < metrics.getNumAttrs(); ++i) {
    const std::string name = metrics.openAttribute(static_cast<unsigned>(i)).getName();
    data.metrics[name] = read_number(metrics, name);
  }
}

// The child's side: parses the file with libhdf5 and sends its fields, or
// the one message that says why it cannot.
void parse_and_send(const fs::path& file, int fd, int version) {
  bake_stream::Out out(fd);
  try {
    H5::Exception::dontPrint();
    file_bytes = fs::file_size(file);
    reading_now = "the file's superblock";
    H5::H5File h5(file.string(), H5F_ACC_RDONLY);
    require_no_external_links(h5);
    BakeData data;
    read_header(h5, data, version);
    read_mesh(h5, data);
    read_receivers(h5, data, version);
    read_transfer(h5, data, out);
    read_compressed(h5, data);
    read_states_and_metrics(h5, data);
    bake_stream::bake_fields(out, data);
  } catch (const H5::Exception& e) {
    out.fail(file.string() + ": damaged bake file: reading " + reading_now + " failed (" +
             e.getDetailMsg() + ")");
  } catch (const std::bad_alloc&) {
    out.fail(file.string() + ": damaged bake file: reading " + reading_now +
             " asks for more memory than such a file can need");
  } catch (const std::exception& e) {
    out.fail(file.string() + ": bad bake file: " + e.what());
  }
}

}  // namespace

BakeData read_bake(const fs::path& file, const ReadOptions& options) {
  // Length and checksum first: a damaged file never reaches libhdf5's parser.
  const int version = verify_bake_file(file);
  if (version != kBakeFormatVersion && version != kReceiversFormatVersion)
    throw Error(file.string() + ": bake format version " + std::to_string(version) +
                ", but this build reads versions " + std::to_string(kBakeFormatVersion) + " and " +
                std::to_string(kReceiversFormatVersion) + "; re-bake the scene");
  // A crafted file with a valid checksum still reaches libhdf5, whose
  // defects (heap overflows, huge allocations, endless loops) it may
  // trigger: the file is parsed in a child process with bounded memory
  // and processor time, and only checked values cross back.
  const double bytes = double(fs::file_size(file));
  const double seconds = kParseSeconds + bytes / kParseBytesPerSecond;
  const ChildLimits limits{kParseMemory + 2 * bytes, seconds, seconds + kParseSeconds};
  BakeData data;
  exchange_with_child(
      file.string(), limits, [&](int fd) { parse_and_send(file, fd, version); },
      [&](int fd) {
        bake_stream::In in(fd, bytes, options, data, limits.idle_seconds);
        try {
          bake_stream::bake_fields(in, data);
          check_bake_values(data);
        } catch (const bake_stream::ParseRefused&) {
          throw;
        } catch (const Error& e) {
          throw Error(file.string() + ": bad bake file: " + e.what());
        }
      });
  return data;
}

}  // namespace prt
