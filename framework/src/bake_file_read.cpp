// The bake file's reader: the seal (length, CRC) first, so a damaged file
// never reaches libhdf5's parser, then every field with its size, type and
// range checked; any failure names the file and what was being read.
#include <H5Cpp.h>

#include "bake_hdf5.hpp"
#include "bake_userblock.hpp"
#include "prt/bake_file.hpp"
#include "prt/error.hpp"
#include "prt/memory.hpp"
#include "prt/row_file.hpp"

namespace prt {
namespace fs = std::filesystem;
using namespace bake_hdf5;

namespace {

// The root's attributes: format, scene, plug-ins, albedo.
void read_header(const H5::H5File& h5, BakeData& data) {
  H5::Group root = open_group(h5, "/");
  if (!root.attrExists("format") || read_text(root, "format") != kFormatName)
    throw Error("it is an HDF5 file but not a PRT bake");
  if (read_number(root, "format_version") != kBakeFormatVersion)
    throw Error("its header and its format_version attribute disagree");
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
  data.mesh.validate("mesh");
}

// Colour materials: how many channel transfers, and which one each colour
// channel reads (absent: one transfer).
void read_channel_groups(const H5::Group& transfer, TransferSignal& signal) {
  if (!transfer.attrExists("channel_groups")) return;
  signal.channel_groups = static_cast<int>(read_count(transfer, "channel_groups", 3));
  if (signal.channel_groups < 1)
    throw Error("the transfer has " + std::to_string(signal.channel_groups) + " channel groups");
  for (int c = 0; c < 3; ++c) {
    const auto group =
        static_cast<int>(read_count(transfer, std::string("group_of_channel_") + "rgb"[c], 2));
    if (group >= signal.channel_groups)
      throw Error("colour channel " + std::to_string(c) + " reads transfer " +
                  std::to_string(group) + " of " + std::to_string(signal.channel_groups));
    signal.group_of_channel[std::size_t(c)] = group;
  }
}

// The transfer (into a row file beside the budget when it would not fit)
// and its direct part.
void read_transfer(const H5::H5File& h5, const ReadOptions& options, BakeData& data) {
  const H5::Group root = open_group(h5, "/");
  H5::Group transfer = open_group(h5, "transfer");
  data.transfer.kind = read_text(transfer, "kind");
  data.material = read_text(transfer, "material");
  data.bounces = static_cast<int>(read_count(transfer, "bounces", 1000));
  data.subsurface = read_count(transfer, "subsurface", 1) != 0;
  if (data.transfer.kind != "diffuse" && data.transfer.kind != "glossy")
    throw Error("unknown transfer kind \"" + data.transfer.kind + "\"");
  data.transfer.exit_rows = static_cast<int>(read_count(transfer, "exit_rows", 1 << 20));
  if (data.transfer.glossy() ? data.transfer.exit_rows < 1 : data.transfer.exit_rows != 1)
    throw Error("transfer kind \"" + data.transfer.kind + "\" with " +
                std::to_string(data.transfer.exit_rows) + " exit rows");
  if (data.transfer.glossy()) data.exit = read_plugin(root, "exit_basis");
  read_channel_groups(transfer, data.transfer);
  hsize_t transfer_rows = 0, transfer_cols = 0;
  const H5::DataSet transfer_set =
      checked_dataset(transfer, "coefficients", H5T_FLOAT, transfer_rows, transfer_cols);
  const double transfer_bytes = double(transfer_rows) * double(transfer_cols) * 4,
               beside = kMeshBytesPerVertex * double(data.mesh.vertex_count());
  if (options.memory_budget > 0 && transfer_bytes + beside > options.memory_budget)
    data.transfer.file = read_rows_to_file(transfer_set, "coefficients", transfer_rows,
                                           transfer_cols, options.rows_folder);
  else
    data.transfer.coefficients = read_matrix(transfer, "coefficients");
  if (data.transfer.vertices() != static_cast<Eigen::Index>(data.mesh.vertex_count()))
    throw Error("the transfer has " + std::to_string(data.transfer.vertices()) + " rows for " +
                std::to_string(data.mesh.vertex_count()) + " vertices");
  if (data.bounces > 0 && transfer.nameExists("direct_coefficients")) {
    data.direct.kind = data.transfer.kind;
    data.direct.exit_rows = data.transfer.exit_rows;
    data.direct.channel_groups = data.transfer.channel_groups;
    data.direct.group_of_channel = data.transfer.group_of_channel;
    data.direct.coefficients = read_matrix(transfer, "direct_coefficients");
    if (data.direct.coefficients.rows() != data.transfer.vertices() ||
        data.direct.coefficients.cols() != data.transfer.dimension())
      throw Error("the direct transfer's shape differs from the transfer's");
  }
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
  for (auto n : counts) total += n;
  const Eigen::Index columns = data.transfer.dimension();
  if (columns != c.dimension)
    throw Error("the transfer has " + std::to_string(columns) +
                " columns but the compressed dimension is " + std::to_string(c.dimension));
  if (columns % (Eigen::Index(data.transfer.exit_rows) * data.transfer.channel_groups) != 0)
    throw Error("the transfer's " + std::to_string(columns) +
                " columns are not a whole number of exit-basis rows (" +
                std::to_string(data.transfer.exit_rows) + ") x channel transfers (" +
                std::to_string(data.transfer.channel_groups) + ")");
  if (static_cast<Eigen::Index>(counts.size()) != c.clusters() || total != stacked.rows() ||
      stacked.cols() != c.dimension || data.transfer.vertices() != c.vertices())
    throw Error("compressed transfer has inconsistent sizes");
  for (Eigen::Index k = 0, row = 0; k < c.clusters(); row += counts[k++]) {
    if (counts[k] < 0 || counts[k] > c.components)
      throw Error("cluster " + std::to_string(k) + " has " + std::to_string(counts[k]) +
                  " components, outside [0, " + std::to_string(c.components) + "]");
    c.representatives.push_back(stacked.middleRows(row, counts[k]));
  }
  c.validate(static_cast<Eigen::Index>(data.mesh.vertex_count()));
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

}  // namespace

BakeData read_bake(const fs::path& file, const ReadOptions& options) {
  H5::Exception::dontPrint();
  // Length and checksum first: a damaged file never reaches libhdf5's parser.
  const int version = verify_bake_file(file);
  if (version != kBakeFormatVersion)
    throw Error(file.string() + ": bake format version " + std::to_string(version) +
                ", but this build reads version " + std::to_string(kBakeFormatVersion) +
                "; re-bake the scene");
  file_bytes = fs::file_size(file);
  BakeData data;
  try {
    reading_now = "the file's superblock";
    H5::H5File h5(file.string(), H5F_ACC_RDONLY);
    require_no_external_links(h5);
    read_header(h5, data);
    read_mesh(h5, data);
    read_transfer(h5, options, data);
    read_compressed(h5, data);
    read_states_and_metrics(h5, data);
  } catch (const H5::Exception& e) {
    throw Error(file.string() + ": damaged bake file: reading " + reading_now + " failed (" +
                e.getDetailMsg() + ")");
  } catch (const Error& e) {
    throw Error(file.string() + ": bad bake file: " + e.what());
  }
  return data;
}

}  // namespace prt
