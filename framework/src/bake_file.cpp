#include "prt/bake_file.hpp"

#include <H5Cpp.h>

#include <fstream>

#include "bake_userblock.hpp"
#include "child_process.hpp"
#include "hdf5_failures.hpp"
#include "prt/error.hpp"
#include "prt/output_file.hpp"
#include "prt/memory.hpp"
#include "prt/row_file.hpp"

namespace prt {
namespace fs = std::filesystem;

namespace {

const char* kFormatName = "prt-bake";

// Variable-length UTF-8, so h5py reads the attribute as str, not bytes.
H5::StrType text_type() {
  H5::StrType type(H5::PredType::C_S1, H5T_VARIABLE);
  type.setCset(H5T_CSET_UTF8);
  return type;
}

void write_text(H5::H5Object& object, const std::string& name, const std::string& value) {
  const H5::StrType type = text_type();
  H5::Attribute a = object.createAttribute(name, type, H5::DataSpace(H5S_SCALAR));
  a.write(type, value);
}

// What the reader was touching when libhdf5 failed, for a message that names
// it ("damaged bake file: reading dataset \"weights\" of /compressed: ...").
thread_local std::string reading_now;

std::string object_name(const H5::H5Object& object) {
  try {
    return object.getObjName();
  } catch (const H5::Exception&) {
    return "?";
  }
}

H5::Group open_group(const H5::H5File& h5, const std::string& name) {
  reading_now = "group \"" + name + "\"";
  if (name != "/" && !h5.nameExists(name)) throw Error("group \"" + name + "\" is missing");
  return h5.openGroup(name);
}

// Attributes are small: anything larger is damage or a crafted file.
constexpr hsize_t kMaxAttributeBytes = 1 << 20;

std::string read_text(const H5::H5Object& object, const std::string& name) {
  reading_now = "attribute \"" + name + "\" of " + object_name(object);
  if (!object.attrExists(name)) throw Error("attribute \"" + name + "\" is missing");
  H5::Attribute a = object.openAttribute(name);
  if (a.getTypeClass() != H5T_STRING || a.getSpace().getSimpleExtentNpoints() != 1)
    throw Error("attribute \"" + name + "\" is not a text");
  if (a.getStorageSize() > kMaxAttributeBytes)
    throw Error("attribute \"" + name + "\" is too large");
  std::string value;
  a.read(a.getStrType(), value);
  if (value.size() > kMaxAttributeBytes) throw Error("attribute \"" + name + "\" is too large");
  return value;
}

void write_number(H5::H5Object& object, const std::string& name, double value) {
  H5::Attribute a =
      object.createAttribute(name, H5::PredType::NATIVE_DOUBLE, H5::DataSpace(H5S_SCALAR));
  a.write(H5::PredType::NATIVE_DOUBLE, &value);
}

double read_number(const H5::H5Object& object, const std::string& name) {
  reading_now = "attribute \"" + name + "\" of " + object_name(object);
  if (!object.attrExists(name)) throw Error("attribute \"" + name + "\" is missing");
  H5::Attribute a = object.openAttribute(name);
  if (a.getTypeClass() != H5T_FLOAT || a.getSpace().getSimpleExtentNpoints() != 1)
    throw Error("attribute \"" + name + "\" is not a number");
  double value = 0;
  a.read(H5::PredType::NATIVE_DOUBLE, &value);
  if (!std::isfinite(value)) throw Error("attribute \"" + name + "\" is NaN or infinite");
  return value;
}

// A count stored as a number: a whole number in [0, limit].
std::int64_t read_count(const H5::H5Object& object, const std::string& name, double limit) {
  const double value = read_number(object, name);
  if (value < 0 || value > limit || value != std::floor(value))
    throw Error("attribute \"" + name + "\" = " + std::to_string(value) +
                " is not a count in [0, " + std::to_string(static_cast<std::int64_t>(limit)) + "]");
  return static_cast<std::int64_t>(value);
}

// A group without modification timestamps, so the same bake gives the same bytes.
H5::Group create_group(H5::H5File& file, const char* name) {
  const hid_t properties = H5Pcreate(H5P_GROUP_CREATE);
  H5Pset_obj_track_times(properties, false);
  const hid_t id = H5Gcreate2(file.getId(), name, H5P_DEFAULT, properties, H5P_DEFAULT);
  H5Pclose(properties);
  if (id < 0) throw Error(std::string("cannot create group ") + name);
  H5::Group group(id);
  H5Gclose(id);  // the C++ object took its own reference
  return group;
}

template <class T>
const H5::PredType& h5_type() {
  if constexpr (std::is_same_v<T, float>)
    return H5::PredType::NATIVE_FLOAT;
  else if constexpr (std::is_same_v<T, double>)
    return H5::PredType::NATIVE_DOUBLE;
  else if constexpr (std::is_same_v<T, std::int32_t>)
    return H5::PredType::NATIVE_INT32;
  else
    return H5::PredType::NATIVE_UINT32;
}

// Writes rows x cols values (row-major) as a 2-D dataset, compressed.
template <class T>
void write_array(H5::Group& group, const std::string& name, const T* data, hsize_t rows,
                 hsize_t cols) {
  const hsize_t dims[2] = {rows, cols};
  H5::DSetCreatPropList properties;
  H5Pset_obj_track_times(properties.getId(), false);  // no timestamps: reproducible files
  if (rows > 0 && cols > 0) {
    const hsize_t chunk[2] = {std::min<hsize_t>(rows, 4096), cols};
    properties.setChunk(2, chunk);
  }
  H5::DataSet set = group.createDataSet(name, h5_type<T>(), H5::DataSpace(2, dims), properties);
  if (rows > 0 && cols > 0) set.write(data, h5_type<T>());
}

// The size of the file being read: no dataset may claim more bytes than it.
thread_local hsize_t file_bytes = 0;

// Refuses data stored outside the file (external storage, virtual datasets):
// a bake file must not pull other files' bytes into its values.
void require_contiguous_in_file(const H5::DataSet& set, const std::string& name) {
  const H5::DSetCreatPropList properties = set.getCreatePlist();
  if (H5Pget_external_count(properties.getId()) != 0)
    throw Error("dataset \"" + name + "\" uses external storage (refused: a bake holds its data)");
  if (H5Pget_layout(properties.getId()) == H5D_VIRTUAL)
    throw Error("dataset \"" + name + "\" is a virtual dataset (refused: a bake holds its data)");
}

// Opens the 2-D dataset `name` of element class `expected`, refusing one
// stored outside the file or declaring more values than it stores (checked
// before anything is allocated for it); rows x cols is its shape.
H5::DataSet checked_dataset(const H5::Group& group, const std::string& name, H5T_class_t expected,
                            hsize_t& rows, hsize_t& cols) {
  reading_now = "dataset \"" + name + "\" of " + object_name(group);
  if (!group.nameExists(name)) throw Error("dataset \"" + name + "\" is missing");
  H5::DataSet set = group.openDataSet(name);
  require_contiguous_in_file(set, name);
  H5::DataSpace space = set.getSpace();
  if (space.getSimpleExtentNdims() != 2) throw Error("dataset \"" + name + "\" is not 2-D");
  hsize_t dims[2];
  space.getSimpleExtentDims(dims);
  rows = dims[0], cols = dims[1];
  if (set.getTypeClass() != expected)
    throw Error("dataset \"" + name + "\" has the wrong element type");
  // Stored uncompressed, so its bytes must be in the file.
  const double bytes = static_cast<double>(rows) * static_cast<double>(cols) *
                       static_cast<double>(set.getDataType().getSize());
  if (bytes > static_cast<double>(file_bytes) ||
      (bytes > 0 && static_cast<double>(set.getStorageSize()) < bytes))
    throw Error("dataset \"" + name + "\" declares " + std::to_string(rows) + " x " +
                std::to_string(cols) + " values that are not stored in the file");
  return set;
}

template <class T>
std::vector<T> read_array(const H5::Group& group, const std::string& name, hsize_t& rows,
                          hsize_t& cols) {
  H5::DataSet set = checked_dataset(
      group, name, std::is_floating_point_v<T> ? H5T_FLOAT : H5T_INTEGER, rows, cols);
  std::vector<T> values(rows * cols);
  if (!values.empty()) set.read(values.data(), h5_type<T>());
  if constexpr (std::is_floating_point_v<T>)
    for (std::size_t i = 0; i < values.size(); ++i)
      if (!std::isfinite(values[i]))
        throw Error("dataset \"" + name + "\" has a NaN or infinite value at row " +
                    std::to_string(i / std::max<hsize_t>(cols, 1)));
  return values;
}

// The scene's text, of any size: a 1-D dataset of bytes.
void write_bytes(H5::H5Object& parent, const std::string& name, const std::string& text) {
  const hsize_t size = text.size();
  H5::DSetCreatPropList properties;
  H5Pset_obj_track_times(properties.getId(), false);
  H5::DataSet set =
      parent.createDataSet(name, H5::PredType::NATIVE_UINT8, H5::DataSpace(1, &size), properties);
  if (size > 0) set.write(text.data(), H5::PredType::NATIVE_UINT8);
}

std::string read_bytes(const H5::Group& group, const std::string& name) {
  reading_now = "dataset \"" + name + "\" of " + object_name(group);
  if (!group.nameExists(name)) throw Error("dataset \"" + name + "\" is missing");
  H5::DataSet set = group.openDataSet(name);
  require_contiguous_in_file(set, name);
  H5::DataSpace space = set.getSpace();
  if (space.getSimpleExtentNdims() != 1 || set.getTypeClass() != H5T_INTEGER ||
      set.getDataType().getSize() != 1)
    throw Error("dataset \"" + name + "\" is not a byte string");
  hsize_t size = 0;
  space.getSimpleExtentDims(&size);
  if (size > file_bytes || (size > 0 && set.getStorageSize() < size))
    throw Error("dataset \"" + name + "\" declares bytes that are not stored in the file");
  std::string text(size, '\0');
  if (size > 0) set.read(text.data(), H5::PredType::NATIVE_UINT8);
  return text;
}

// External links would let a bake file read other files; refused anywhere.
herr_t refuse_external_link(hid_t, const char* name, const H5L_info_t* info, void* found) {
  if (info->type == H5L_TYPE_EXTERNAL || info->type >= H5L_TYPE_UD_MIN) {
    *static_cast<std::string*>(found) = name;
    return 1;
  }
  return 0;
}

void require_no_external_links(const H5::H5File& h5) {
  std::string found;
  if (H5Lvisit(h5.getId(), H5_INDEX_NAME, H5_ITER_NATIVE, refuse_external_link, &found) < 0)
    throw Error("cannot list the file's objects");
  if (!found.empty())
    throw Error("\"" + found + "\" is an external link (refused: a bake holds its data)");
}

void write_matrix(H5::Group& group, const std::string& name, const MatrixXfRow& m) {
  write_array(group, name, m.data(), m.rows(), m.cols());
}

// The same dataset as write_matrix, filled chunk by chunk from `rows`.
void write_streamed(H5::Group& group, const std::string& name, const BakeData::StreamedRows& rows) {
  const hsize_t dims[2] = {hsize_t(rows.rows), hsize_t(rows.cols)};
  const hsize_t chunk_rows = std::min<hsize_t>(dims[0], 4096);
  H5::DSetCreatPropList properties;
  H5Pset_obj_track_times(properties.getId(), false);
  const hsize_t chunk[2] = {chunk_rows, dims[1]};
  properties.setChunk(2, chunk);
  H5::DataSet set = group.createDataSet(name, h5_type<float>(), H5::DataSpace(2, dims), properties);
  MatrixXfRow block;
  for (hsize_t first = 0; first < dims[0]; first += chunk_rows) {
    const hsize_t count[2] = {std::min(chunk_rows, dims[0] - first), dims[1]};
    const hsize_t offset[2] = {first, 0};
    rows.read(Eigen::Index(first), Eigen::Index(count[0]), block);
    if (block.rows() != Eigen::Index(count[0]) || block.cols() != rows.cols)
      throw Error("dataset \"" + name + "\": its rows came in the wrong shape");
    H5::DataSpace file_space = set.getSpace();
    file_space.selectHyperslab(H5S_SELECT_SET, count, offset);
    set.write(block.data(), h5_type<float>(), H5::DataSpace(2, count), file_space);
  }
}

// A transfer's rows read from its file, a block at a time, for write_streamed.
BakeData::StreamedRows rows_of_file(const TransferSignal& signal) {
  BakeData::StreamedRows rows;
  rows.rows = signal.vertices();
  rows.cols = signal.dimension();
  rows.read = [&signal](Eigen::Index first, Eigen::Index count, MatrixXfRow& out) {
    out = signal.rows().middleRows(first, count);
    signal.release(first, first + count);
  };
  return rows;
}

// The float dataset `set` (rows x cols, from checked_dataset), read a block of rows at a time
// into a RowFile in `folder`: never whole in memory. Values are checked as
// read_array checks them.
std::shared_ptr<RowFile> read_rows_to_file(const H5::DataSet& set, const std::string& name,
                                           hsize_t rows, hsize_t cols, const fs::path& folder) {
  auto file = RowFile::create(folder, Eigen::Index(rows), Eigen::Index(cols));
  MatrixXfRow block;
  const hsize_t step = 4096;
  for (hsize_t first = 0; first < rows; first += step) {
    const hsize_t count[2] = {std::min(step, rows - first), cols}, offset[2] = {first, 0};
    block.resize(Eigen::Index(count[0]), Eigen::Index(cols));
    H5::DataSpace file_space = set.getSpace();
    file_space.selectHyperslab(H5S_SELECT_SET, count, offset);
    set.read(block.data(), h5_type<float>(), H5::DataSpace(2, count), file_space);
    for (Eigen::Index r = 0; r < block.rows(); ++r)
      if (!block.row(r).allFinite())
        throw Error("dataset \"" + name + "\" has a NaN or infinite value at row " +
                    std::to_string(first + hsize_t(r)));
    file->write(Eigen::Index(first), block);
  }
  file->map();
  return file;
}

MatrixXfRow read_matrix(const H5::Group& group, const std::string& name) {
  hsize_t rows, cols;
  auto values = read_array<float>(group, name, rows, cols);
  return Eigen::Map<MatrixXfRow>(values.data(), rows, cols);
}

template <class V, class T>
void write_vectors(H5::Group& group, const std::string& name, const std::vector<V>& items) {
  std::vector<T> flat;
  flat.reserve(items.size() * 3);
  for (const auto& item : items)
    for (int c = 0; c < 3; ++c) flat.push_back(static_cast<T>(item[c]));
  write_array(group, name, flat.data(), items.size(), 3);
}

template <class V, class T>
std::vector<V> read_vectors(const H5::Group& group, const std::string& name) {
  hsize_t rows, cols;
  auto flat = read_array<T>(group, name, rows, cols);
  if (cols != 3) throw Error("dataset \"" + name + "\" must have 3 columns");
  std::vector<V> items(rows);
  for (hsize_t r = 0; r < rows; ++r)
    for (int c = 0; c < 3; ++c) items[r][c] = flat[r * 3 + c];
  return items;
}

void write_plugin(H5::H5Object& object, const std::string& prefix, const PluginRecord& p) {
  write_text(object, prefix + "_plugin", p.name);
  write_text(object, prefix + "_version", p.version);
  write_text(object, prefix + "_parameters", p.parameters);
}

PluginRecord read_plugin(const H5::H5Object& object, const std::string& prefix) {
  return {read_text(object, prefix + "_plugin"), read_text(object, prefix + "_version"),
          read_text(object, prefix + "_parameters")};
}

}  // namespace

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
  data.compressed.validate(static_cast<Eigen::Index>(data.mesh.vertex_count()));
  const bool streamed = data.streamed_transfer.rows > 0;
  const Eigen::Index transfer_rows =
      streamed ? data.streamed_transfer.rows : data.transfer.vertices();
  const Eigen::Index transfer_cols =
      streamed ? data.streamed_transfer.cols : data.transfer.dimension();
  if (transfer_rows != static_cast<Eigen::Index>(data.mesh.vertex_count()))
    throw Error(file.string() + ": transfer rows do not match the mesh's vertices");
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
    seal_bake_file(temporary, kBakeFormatVersion, file);
  });
}

namespace {

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
      H5::Group root = open_group(h5, "/");
      write_text(root, "format", kFormatName);
      write_number(root, "format_version", kBakeFormatVersion);
      write_text(root, "scene_file", data.scene_file);
      write_bytes(root, "scene_text", data.scene_text);
      write_text(root, "transport", data.transport);
      write_plugin(root, "basis", data.basis);
      write_plugin(root, "compressor", data.compressor);
      if (data.transfer.glossy()) write_plugin(root, "exit_basis", data.exit);
      for (int c = 0; c < 3; ++c)
        write_number(root, "albedo_" + std::string(1, "rgb"[c]), data.albedo[c]);

      H5::Group mesh = create_group(h5, "mesh");
      write_vectors<Eigen::Vector3f, float>(mesh, "positions", data.mesh.positions);
      write_vectors<Eigen::Vector3f, float>(mesh, "normals", data.mesh.normals);
      write_vectors<std::array<std::uint32_t, 3>, std::uint32_t>(mesh, "triangles",
                                                                 data.mesh.triangles);

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

      const CompressedTransfer& c = data.compressed;
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

      for (const auto& [group, basis_state] :
           {std::pair{"basis_state", &data.basis_state}, {"exit_state", &data.exit_state}}) {
        H5::Group state = create_group(h5, group);
        for (const auto& [name, m] : basis_state->matrices) {
          const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> row_major =
              m;
          write_array(state, name, row_major.data(), m.rows(), m.cols());
        }
      }
      H5::Group metrics = create_group(h5, "metrics");
      for (const auto& [name, value] : data.metrics) write_number(metrics, name, value);
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

    H5::Group mesh = open_group(h5, "mesh");
    data.mesh.positions = read_vectors<Eigen::Vector3f, float>(mesh, "positions");
    data.mesh.normals = read_vectors<Eigen::Vector3f, float>(mesh, "normals");
    data.mesh.triangles =
        read_vectors<std::array<std::uint32_t, 3>, std::uint32_t>(mesh, "triangles");
    data.mesh.validate("mesh");

    hsize_t rows, cols;
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
    if (transfer.attrExists("channel_groups")) {  // colour materials (absent: one transfer)
      data.transfer.channel_groups = static_cast<int>(read_count(transfer, "channel_groups", 3));
      if (data.transfer.channel_groups < 1)
        throw Error("the transfer has " + std::to_string(data.transfer.channel_groups) +
                    " channel groups");
      for (int c = 0; c < 3; ++c) {
        const auto group =
            static_cast<int>(read_count(transfer, std::string("group_of_channel_") + "rgb"[c], 2));
        if (group >= data.transfer.channel_groups)
          throw Error("colour channel " + std::to_string(c) + " reads transfer " +
                      std::to_string(group) + " of " +
                      std::to_string(data.transfer.channel_groups));
        data.transfer.group_of_channel[std::size_t(c)] = group;
      }
    }
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
  } catch (const H5::Exception& e) {
    throw Error(file.string() + ": damaged bake file: reading " + reading_now + " failed (" +
                e.getDetailMsg() + ")");
  } catch (const Error& e) {
    throw Error(file.string() + ": bad bake file: " + e.what());
  }
  return data;
}

}  // namespace prt
