// HDF5 bake files: one file per bake, written atomically (temp + rename) and
// refused with a clear message when damaged or of another format version.
#pragma once
#include <Eigen/Core>
#include <filesystem>
#include <functional>
#include <map>
#include <string>

#include "prt/basis.hpp"
#include "prt/mesh.hpp"
#include "prt/receivers.hpp"
#include "prt/transfer.hpp"

namespace prt {

// 2: glossy matrices, material, bounces and subsurface recorded.
// 3: a checksummed PRT-BAKE user block; scene text as a dataset; UTF-8 text attributes.
// 4: the exit basis of glossy transfer is a plug-in: /exit_basis record and
//    /exit_state group replace exit_order / exit_kept; /transfer exit_rows.
// 5: receivers other than the mesh's vertices (a /receivers group: probes).
//    A bake at vertices is still written as version 4, byte for byte as before.
constexpr int kBakeFormatVersion = 4;
constexpr int kReceiversFormatVersion = 5;

struct PluginRecord {
  std::string name, version, parameters;
};
// The compressor record of a bake that kept its transfer exact (no compressor ran).
inline constexpr const char* kExactRecord = "exact";
// "sh 1.0.0 (order = 6)": name, version and every parameter on one line.
std::string one_line(const PluginRecord& plugin);

struct BakeData {
  std::string scene_file, scene_text;
  PluginRecord basis, compressor;
  PluginRecord exit;      // glossy only: the hemisphere basis of exit radiance
  std::string transport;  // e.g. "fibonacci 1024 shadowed seed=1"
  Mesh mesh;  // the scene's geometry (with its atlas at texels); at vertex receivers, one row per
              // vertex
  Receivers receivers;  // where the transfer's rows are (default: the mesh's vertices)
  Eigen::Vector3f albedo{1, 1, 1};
  std::string material = "lambert kd=1";  // the BRDF the transfer was baked for
  int bounces = 0;                        // inter-reflection bounces included
  bool subsurface = false;                // subsurface term included
  TransferSignal transfer;
  // bounces > 0: the transfer without inter-reflection (same shape), kept so
  // that prt render --compare can show what the bounces bring; else empty.
  TransferSignal direct;
  // Set instead of transfer.coefficients' rows (which then has none, only
  // its kind and layout) when the transfer is too large to hold: write_bake
  // asks it for rows [first, first + count) into `out` (count x cols).
  struct StreamedRows {
    Eigen::Index rows = 0, cols = 0;
    std::function<void(Eigen::Index first, Eigen::Index count, MatrixXfRow& out)> read;
  } streamed_transfer;
  CompressedTransfer compressed;
  BasisState basis_state;
  BasisState exit_state;                  // glossy only
  std::map<std::string, double> metrics;  // timings (s), squared error, ...

  // One vertex per transfer row: the mesh at vertex receivers, the probes'
  // points otherwise (for compressors and encode reports).
  const Mesh& row_mesh() const { return receivers.at_vertices() ? mesh : receivers.points; }
  // The transfer's rows: one per receiver.
  std::size_t receiver_count() const {
    return receivers.probes()   ? receivers.grid.count()
           : receivers.texels() ? receivers.atlas.texels.size()
                                : mesh.vertex_count();
  }
  int format_version() const {
    return receivers.at_vertices() ? kBakeFormatVersion : kReceiversFormatVersion;
  }
};

// A transfer whose rows are in a file (TransferSignal::on_disk) is written
// from it a block of rows at a time.
void write_bake(const std::filesystem::path& file, const BakeData& data);

// memory_budget > 0: a transfer that does not fit in it beside the mesh is
// read a block of rows at a time into a RowFile in rows_folder (so the
// compressors read it in passes) instead of memory.
struct ReadOptions {
  double memory_budget = 0;
  std::filesystem::path rows_folder = ".";
};
BakeData read_bake(const std::filesystem::path& file, const ReadOptions& options = {});

}  // namespace prt
