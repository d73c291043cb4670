#include "bake_values.hpp"

#include <cmath>
#include <cstdio>

#include "prt/error.hpp"

namespace prt {

namespace {

// The texts a bake holds end up in messages and in `prt info`: each must be
// UTF-8 without control bytes (line breaks only where a record has lines).
void check_text(const std::string& text, const std::string& field, bool lines = false) {
  for (std::size_t i = 0; i < text.size();) {
    const auto byte = static_cast<unsigned char>(text[i]);
    const std::size_t length = byte < 0x80         ? 1
                               : (byte >> 5) == 6  ? 2
                               : (byte >> 4) == 14 ? 3
                               : (byte >> 3) == 30 ? 4
                                                   : 0;
    bool ok = length > 0 && i + length <= text.size();
    for (std::size_t k = 1; ok && k < length; ++k)
      ok = (static_cast<unsigned char>(text[i + k]) >> 6) == 2;
    if (byte < 0x80) ok = (byte >= 0x20 && byte != 0x7f) || byte == '\t' || (lines && byte == '\n');
    if (!ok) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%02x", byte);
      throw Error(field + " holds a byte that is not text (" + hex + " at offset " +
                  std::to_string(i) + ")");
    }
    i += length;
  }
}

void check_texts(const BakeData& data) {
  check_text(data.scene_file, "attribute \"scene_file\"");
  check_text(data.transport, "attribute \"transport\"");
  check_text(data.material, "attribute \"material\"");
  check_text(data.transfer.kind, "attribute \"kind\"");
  check_text(data.compressed.compressor, "attribute \"compressor\" of /compressed");
  for (const auto& [prefix, record] : {std::pair{"basis", &data.basis},
                                       {"compressor", &data.compressor},
                                       {"exit_basis", &data.exit}}) {
    const std::string attribute = std::string("attribute \"") + prefix;
    check_text(record->name, attribute + "_plugin\"");
    check_text(record->version, attribute + "_version\"");
    check_text(record->parameters, attribute + "_parameters\"", true);
  }
  for (const auto& [name, value] : data.metrics) check_text(name, "a metric's name");
  for (const auto* state : {&data.basis_state, &data.exit_state})
    for (const auto& [name, matrix] : state->matrices) check_text(name, "a basis state's name");
}

void check_mesh(const Mesh& mesh) {
  mesh.validate("mesh");
  for (std::size_t v = 0; v < mesh.normals.size(); ++v)
    if (!mesh.normals[v].allFinite())
      throw Error("mesh: normal " + std::to_string(v) + " is NaN or infinite");
}

void check_layout(const TransferSignal& transfer, int bounces) {
  if (transfer.kind != "diffuse" && transfer.kind != "glossy" && transfer.kind != "incident")
    throw Error("unknown transfer kind \"" + transfer.kind + "\"");
  if (transfer.kind != "diffuse" ? transfer.exit_rows < 1 : transfer.exit_rows != 1)
    throw Error("transfer kind \"" + transfer.kind + "\" with " +
                std::to_string(transfer.exit_rows) + " exit rows");
  if (bounces < 0 || bounces > 1000)
    throw Error("attribute \"bounces\" = " + std::to_string(bounces) + " is outside [0, 1000]");
  if (transfer.channel_groups < 1 || transfer.channel_groups > 3)
    throw Error("the transfer has " + std::to_string(transfer.channel_groups) +
                " channel groups (1 to 3)");
  for (int c = 0; c < 3; ++c) {
    const int group = transfer.group_of_channel[std::size_t(c)];
    if (group < 0 || group >= transfer.channel_groups)
      throw Error("colour channel " + std::to_string(c) + " reads transfer " +
                  std::to_string(group) + " of " + std::to_string(transfer.channel_groups));
  }
}

void check_transfer(BakeData& data) {
  const TransferSignal& transfer = data.transfer;
  if (transfer.vertices() != static_cast<Eigen::Index>(data.receiver_count()))
    throw Error("the transfer has " + std::to_string(transfer.vertices()) + " rows for " +
                std::to_string(data.receiver_count()) + " " +
                (data.receivers.at_vertices() ? "vertices" : data.receivers.kind));
  if ((transfer.kind == "incident") != data.receivers.probes())
    throw Error("transfer kind \"" + transfer.kind + "\" at " + data.receivers.kind);

  const Eigen::Index columns = transfer.dimension();
  if (columns % (Eigen::Index(transfer.exit_rows) * transfer.channel_groups) != 0)
    throw Error("the transfer's " + std::to_string(columns) +
                " columns are not a whole number of exit-basis rows (" +
                std::to_string(transfer.exit_rows) + ") x channel transfers (" +
                std::to_string(transfer.channel_groups) + ")");
  TransferSignal& direct = data.direct;
  if (direct.coefficients.size() == 0 && direct.coefficients.rows() == 0) return;
  if (data.bounces == 0) throw Error("a direct transfer without bounces");
  if (direct.coefficients.rows() != transfer.vertices() || direct.coefficients.cols() != columns)
    throw Error("the direct transfer's shape differs from the transfer's");
  direct.kind = transfer.kind;
  direct.exit_rows = transfer.exit_rows;
  direct.channel_groups = transfer.channel_groups;
  direct.group_of_channel = transfer.group_of_channel;
}

void check_compressed(const BakeData& data) {
  const CompressedTransfer& c = data.compressed;
  if (c.dimension != data.transfer.dimension())
    throw Error("the transfer has " + std::to_string(data.transfer.dimension()) +
                " columns but the compressed dimension is " + std::to_string(c.dimension));
  if (c.components < 0) throw Error("a negative number of components");
  c.validate(static_cast<Eigen::Index>(data.receiver_count()));
}

// A texel bake: its atlas, one point (finite, unit normal) per texel, and
// the mesh's texture coordinates the renderers look the texels up through.
void check_texels(const BakeData& data) {
  const Receivers& r = data.receivers;
  check_texel_atlas(r.atlas, "/receivers");
  const std::size_t n = r.atlas.texels.size();
  if (r.points.positions.size() != n || r.points.normals.size() != n)
    throw Error("/receivers has " + std::to_string(r.points.positions.size()) + " positions and " +
                std::to_string(r.points.normals.size()) + " normals for " + std::to_string(n) +
                " texels");
  for (std::size_t i = 0; i < n; ++i)
    if (!r.points.positions[i].allFinite() || !(std::abs(r.points.normals[i].norm() - 1) < 1e-3f))
      throw Error("/receivers: texel " + std::to_string(i) +
                  " has a non-finite position or a normal that is not unit length");
  if (data.mesh.uvs.size() != data.mesh.vertex_count())
    throw Error("/mesh has " + std::to_string(data.mesh.uvs.size()) + " texture coordinates for " +
                std::to_string(data.mesh.vertex_count()) +
                " vertices; texel receivers need one per vertex");
}

void check_finite(const BasisState& state, const char* group) {
  for (const auto& [name, matrix] : state.matrices)
    if (!matrix.allFinite())
      throw Error("dataset \"" + name + "\" of /" + group + " has a NaN or infinite value");
}

}  // namespace

void check_bake_values(BakeData& data) {
  check_texts(data);
  check_mesh(data.mesh);
  if (data.receivers.probes()) {
    check_probe_grid(data.receivers.grid, "/receivers");
    if (data.receivers.valid.size() != data.receiver_count())
      throw Error("/receivers/valid has " + std::to_string(data.receivers.valid.size()) +
                  " flags for " + std::to_string(data.receiver_count()) + " probes");
    for (std::uint8_t flag : data.receivers.valid)
      if (flag > 1) throw Error("/receivers/valid holds a value other than 0 or 1");
    data.receivers = Receivers::probes_on(data.receivers.grid, std::move(data.receivers.valid));
  } else if (data.receivers.texels()) {
    check_texels(data);
  } else if (data.receivers.kind != "vertices") {
    throw Error("unknown receivers \"" + data.receivers.kind + "\"");
  }
  if (!data.albedo.allFinite()) throw Error("the albedo is NaN or infinite");
  check_layout(data.transfer, data.bounces);
  check_transfer(data);
  check_compressed(data);
  check_finite(data.basis_state, "basis_state");
  check_finite(data.exit_state, "exit_state");
  for (const auto& [name, value] : data.metrics)
    if (!std::isfinite(value)) throw Error("metric \"" + name + "\" is NaN or infinite");
}

}  // namespace prt
