// The bake file's writer: checks the data, then writes it in a child process
// through a temporary that is sealed (length, CRC) and renamed into place.
#include "prt/bake_file.hpp"

#include <H5Cpp.h>

#include "bake_hdf5.hpp"
#include "bake_userblock.hpp"
#include "child_process.hpp"
#include "hdf5_failures.hpp"
#include "prt/error.hpp"
#include "prt/output_file.hpp"

namespace prt {
namespace fs = std::filesystem;
using namespace bake_hdf5;

std::string one_line(const PluginRecord& plugin) {
  std::string parameters = plugin.parameters;
  while (!parameters.empty() && parameters.back() == '\n') parameters.pop_back();
  for (std::size_t at; (at = parameters.find('\n')) != std::string::npos;)
    parameters.replace(at, 1, ", ");
  return plugin.name + " " + plugin.version + (parameters.empty() ? "" : " (" + parameters + ")");
}

namespace {
// The HDF5 part of write_bake, into `temporary` (`file` names it in messages).
void write_bake_to(const fs::path& temporary, const fs::path& file, const BakeData& data,
                   bool streamed);
}  // namespace

void write_bake(const fs::path& file, const BakeData& data) {
  H5::Exception::dontPrint();
  data.mesh.validate("bake data");
  const auto rows = static_cast<Eigen::Index>(data.receiver_count());
  if (data.receivers.texels()) check_texel_atlas(data.receivers.atlas, file.string());
  if (data.receivers.probes()) {
    check_probe_grid(data.receivers.grid, file.string());
    if (data.receivers.valid.size() != std::size_t(rows))
      throw Error(file.string() + ": " + std::to_string(data.receivers.valid.size()) +
                  " validity flags for " + std::to_string(rows) + " probes; nothing written");
  }
  data.compressed.validate(rows);
  const bool streamed = data.streamed_transfer.rows > 0;
  const Eigen::Index transfer_rows =
      streamed ? data.streamed_transfer.rows : data.transfer.vertices();
  const Eigen::Index transfer_cols =
      streamed ? data.streamed_transfer.cols : data.transfer.dimension();
  if (transfer_rows != rows)
    throw Error(file.string() + ": transfer rows do not match the " +
                (data.receivers.at_vertices() ? "mesh's vertices" : data.receivers.kind));
  const TransferSignal& t = data.transfer;
  bool channels_ok = t.channel_groups >= 1 && t.channel_groups <= 3 && t.exit_rows >= 1 &&
                     transfer_cols % (Eigen::Index(t.exit_rows) * t.channel_groups) == 0;
  for (int group : t.group_of_channel)
    channels_ok = channels_ok && group >= 0 && group < t.channel_groups;
  if (!channels_ok)
    throw Error(file.string() + ": the transfer's " + std::to_string(transfer_cols) + " columns, " +
                std::to_string(t.exit_rows) + " exit rows and " + std::to_string(t.channel_groups) +
                " channel transfers do not fit together (or a colour channel reads a missing "
                "transfer); nothing written");
  // libhdf5 1.10 cannot recover from a failed write: closing the file after a
  // failed flush double-frees (SIGSEGV). The file is written by a child
  // process, which ends at the first failure with its message; this process
  // never holds a half-written HDF5 file.
  write_atomically(file, [&](const fs::path& temporary) {
    run_in_child_process(file.string() + ": writing the bake file",
                         [&] { write_bake_to(temporary, file, data, streamed); });
    seal_bake_file(temporary, data.format_version(), file);
  });
}

namespace {

// The root's attributes: format, scene, plug-ins, albedo.
void write_header(H5::H5File& h5, const BakeData& data) {
  H5::Group root = open_group(h5, "/");
  write_text(root, "format", kFormatName);
  write_number(root, "format_version", data.format_version());
  write_text(root, "scene_file", data.scene_file);
  write_bytes(root, "scene_text", data.scene_text);
  write_text(root, "transport", data.transport);
  write_plugin(root, "basis", data.basis);
  write_plugin(root, "compressor", data.compressor);
  if (data.transfer.glossy() || data.receivers.probes())
    write_plugin(root, "exit_basis", data.exit);
  for (int c = 0; c < 3; ++c)
    write_number(root, "albedo_" + std::string(1, "rgb"[c]), data.albedo[c]);
}

void write_mesh(H5::H5File& h5, const Mesh& m) {
  H5::Group mesh = create_group(h5, "mesh");
  write_vectors<Eigen::Vector3f, float>(mesh, "positions", m.positions);
  write_vectors<Eigen::Vector3f, float>(mesh, "normals", m.normals);
  write_vectors<std::array<std::uint32_t, 3>, std::uint32_t>(mesh, "triangles", m.triangles);
  if (!m.uvs.empty()) write_vectors<Eigen::Vector2f, float>(mesh, "uvs", m.uvs);
}

// Where the transfer's rows are, when not at the mesh's vertices.
void write_receivers(H5::H5File& h5, const Receivers& r) {
  H5::Group receivers = create_group(h5, "receivers");
  write_text(receivers, "kind", r.kind);
  if (r.texels()) {  // the texels and their surface points
    write_number(receivers, "width", r.atlas.width);
    write_number(receivers, "height", r.atlas.height);
    write_array(receivers, "texels", r.atlas.texels.data(), r.atlas.texels.size(), 1);
    write_vectors<Eigen::Vector3f, float>(receivers, "positions", r.points.positions);
    write_vectors<Eigen::Vector3f, float>(receivers, "normals", r.points.normals);
    return;
  }
  write_number(receivers, "spacing", r.grid.spacing);
  for (int a = 0; a < 3; ++a) {
    const std::string axis(1, "xyz"[a]);
    write_number(receivers, "origin_" + axis, r.grid.origin[a]);
    write_number(receivers, "count_" + axis, r.grid.counts[std::size_t(a)]);
  }
  write_array(receivers, "valid", r.valid.data(), r.valid.size(), 1);
}

// The transfer: from memory, from its row file, or streamed from the ranks' slabs.
void write_transfer(H5::H5File& h5, const BakeData& data, bool streamed) {
  H5::Group transfer = create_group(h5, "transfer");
  write_text(transfer, "kind", data.transfer.kind);
  write_text(transfer, "material", data.material);
  write_number(transfer, "bounces", data.bounces);
  write_number(transfer, "subsurface", data.subsurface ? 1 : 0);
  write_number(transfer, "exit_rows", data.transfer.exit_rows);
  write_number(transfer, "channel_groups", data.transfer.channel_groups);
  for (int c = 0; c < 3; ++c)
    write_number(transfer, std::string("group_of_channel_") + "rgb"[c],
                 data.transfer.group_of_channel[std::size_t(c)]);
  if (streamed)
    write_streamed(transfer, "coefficients", data.streamed_transfer);
  else if (data.transfer.on_disk())
    write_streamed(transfer, "coefficients", rows_of_file(data.transfer));
  else
    write_matrix(transfer, "coefficients", data.transfer.coefficients);
  if (data.direct.coefficients.size())
    write_matrix(transfer, "direct_coefficients", data.direct.coefficients);
}

// The compressed form; each cluster's representatives stacked in one dataset.
void write_compressed(H5::H5File& h5, const CompressedTransfer& c) {
  H5::Group compressed = create_group(h5, "compressed");
  write_text(compressed, "compressor", c.compressor);
  write_number(compressed, "components", c.components);
  write_number(compressed, "dimension", static_cast<double>(c.dimension));
  write_array(compressed, "cluster_of_vertex", c.cluster_of_vertex.data(),
              c.cluster_of_vertex.size(), 1);
  write_matrix(compressed, "weights", c.weights);
  write_matrix(compressed, "means", c.means);
  std::vector<std::int32_t> counts(c.clusters());
  Eigen::Index rows = 0;
  for (Eigen::Index k = 0; k < c.clusters(); ++k) rows += counts[k] = c.components_of(k);
  MatrixXfRow stacked(rows, c.dimension);
  for (Eigen::Index k = 0, row = 0; k < c.clusters(); row += counts[k++])
    stacked.middleRows(row, counts[k]) = c.representatives[k];
  write_matrix(compressed, "representatives", stacked);
  write_array(compressed, "components_of_cluster", counts.data(), counts.size(), 1);
  write_array(compressed, "supercluster_of_cluster", c.supercluster_of_cluster.data(),
              c.supercluster_of_cluster.size(), 1);
  write_array(compressed, "weight_index", c.weight_index.data(), c.sparse() ? c.vertices() : 0,
              c.sparse() ? c.components : 0);
}

// The bases' fitted states and the bake's metrics.
void write_states_and_metrics(H5::H5File& h5, const BakeData& data) {
  for (const auto& [group, basis_state] :
       {std::pair{"basis_state", &data.basis_state}, {"exit_state", &data.exit_state}}) {
    H5::Group state = create_group(h5, group);
    for (const auto& [name, m] : basis_state->matrices) {
      const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> row_major = m;
      write_array(state, name, row_major.data(), m.rows(), m.cols());
    }
  }
  H5::Group metrics = create_group(h5, "metrics");
  for (const auto& [name, value] : data.metrics) write_number(metrics, name, value);
}

void write_bake_to(const fs::path& temporary, const fs::path& file, const BakeData& data,
                   bool streamed) {
  Hdf5FailureRecorder failures(file);
  try {
    H5::FileCreatPropList creation;
    creation.setUserblock(kBakeUserBlockSize);
    H5::FileAccPropList access;
    // Closing the file closes whatever a failed close left open.
    access.setFcloseDegree(H5F_CLOSE_STRONG);
    H5::H5File h5(temporary.string(), H5F_ACC_TRUNC, creation, access);
    {  // every object closed before the file, so its close reports the flush
      write_header(h5, data);
      write_mesh(h5, data.mesh);
      if (!data.receivers.at_vertices()) write_receivers(h5, data.receivers);
      write_transfer(h5, data, streamed);
      write_compressed(h5, data.compressed);
      write_states_and_metrics(h5, data);
    }
    h5.close();
  } catch (const H5::Exception& e) {
    throw Error(failures.message(e.getDetailMsg()));
  }
  // Failures inside the wrappers' destructors (a dataset's flush) are only
  // recorded there.
  if (failures.failed()) throw Error(failures.message());
}

}  // namespace

}  // namespace prt
