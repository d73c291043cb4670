// The HDF5 pieces of a bake file, shared by its writer (bake_file.cpp) and
// its reader (bake_file_read.cpp): typed attributes and datasets, with the
// reader's checks (sizes, types, layout inside the file, no external links)
// and a note of what it was reading for messages.
#pragma once
#include <H5Cpp.h>

#include <memory>
#include <string>
#include <vector>

#include "prt/bake_file.hpp"
#include "prt/error.hpp"

namespace prt::bake_hdf5 {
namespace fs = std::filesystem;

inline const char* kFormatName = "prt-bake";

// Variable-length UTF-8, so h5py reads the attribute as str, not bytes.
inline H5::StrType text_type() {
  H5::StrType type(H5::PredType::C_S1, H5T_VARIABLE);
  type.setCset(H5T_CSET_UTF8);
  return type;
}

inline void write_text(H5::H5Object& object, const std::string& name, const std::string& value) {
  const H5::StrType type = text_type();
  H5::Attribute a = object.createAttribute(name, type, H5::DataSpace(H5S_SCALAR));
  a.write(type, value);
}

// What the reader was touching when libhdf5 failed, for a message that names
// it ("damaged bake file: reading dataset \"weights\" of /compressed: ...").
inline thread_local std::string reading_now;

inline std::string object_name(const H5::H5Object& object) {
  try {
    return object.getObjName();
  } catch (const H5::Exception&) {
    return "?";
  }
}

inline H5::Group open_group(const H5::H5File& h5, const std::string& name) {
  reading_now = "group \"" + name + "\"";
  if (name != "/" && !h5.nameExists(name)) throw Error("group \"" + name + "\" is missing");
  return h5.openGroup(name);
}

// Attributes are small: anything larger is damage or a crafted file.
constexpr hsize_t kMaxAttributeBytes = 1 << 20;

inline std::string read_text(const H5::H5Object& object, const std::string& name) {
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

inline void write_number(H5::H5Object& object, const std::string& name, double value) {
  H5::Attribute a =
      object.createAttribute(name, H5::PredType::NATIVE_DOUBLE, H5::DataSpace(H5S_SCALAR));
  a.write(H5::PredType::NATIVE_DOUBLE, &value);
}

inline double read_number(const H5::H5Object& object, const std::string& name) {
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
inline std::int64_t read_count(const H5::H5Object& object, const std::string& name, double limit) {
  const double value = read_number(object, name);
  if (value < 0 || value > limit || value != std::floor(value))
    throw Error("attribute \"" + name + "\" = " + std::to_string(value) +
                " is not a count in [0, " + std::to_string(static_cast<std::int64_t>(limit)) + "]");
  return static_cast<std::int64_t>(value);
}

// A group without modification timestamps, so the same bake gives the same bytes.
inline H5::Group create_group(H5::H5File& file, const char* name) {
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
inline const H5::PredType& h5_type() {
  if constexpr (std::is_same_v<T, float>)
    return H5::PredType::NATIVE_FLOAT;
  else if constexpr (std::is_same_v<T, double>)
    return H5::PredType::NATIVE_DOUBLE;
  else if constexpr (std::is_same_v<T, std::int32_t>)
    return H5::PredType::NATIVE_INT32;
  else if constexpr (std::is_same_v<T, std::uint8_t>)
    return H5::PredType::NATIVE_UINT8;
  else
    return H5::PredType::NATIVE_UINT32;
}

// Writes rows x cols values (row-major) as a 2-D dataset, compressed.
template <class T>
inline void write_array(H5::Group& group, const std::string& name, const T* data, hsize_t rows,
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
inline thread_local hsize_t file_bytes = 0;

// Refuses data stored outside the file (external storage, virtual datasets):
// a bake file must not pull other files' bytes into its values.
inline void require_contiguous_in_file(const H5::DataSet& set, const std::string& name) {
  const H5::DSetCreatPropList properties = set.getCreatePlist();
  if (H5Pget_external_count(properties.getId()) != 0)
    throw Error("dataset \"" + name + "\" uses external storage (refused: a bake holds its data)");
  if (H5Pget_layout(properties.getId()) == H5D_VIRTUAL)
    throw Error("dataset \"" + name + "\" is a virtual dataset (refused: a bake holds its data)");
}

// Opens the 2-D dataset `name` of element class `expected`, refusing one
// stored outside the file or declaring more values than it stores (checked
// before anything is allocated for it); rows x cols is its shape.
inline H5::DataSet checked_dataset(const H5::Group& group, const std::string& name,
                                   H5T_class_t expected, hsize_t& rows, hsize_t& cols) {
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
  // A dimension beyond the file's bytes is damage even when the other is 0.
  if (bytes > static_cast<double>(file_bytes) || rows > file_bytes || cols > file_bytes ||
      (bytes > 0 && static_cast<double>(set.getStorageSize()) < bytes))
    throw Error("dataset \"" + name + "\" declares " + std::to_string(rows) + " x " +
                std::to_string(cols) + " values that are not stored in the file");
  return set;
}

template <class T>
inline std::vector<T> read_array(const H5::Group& group, const std::string& name, hsize_t& rows,
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
inline void write_bytes(H5::H5Object& parent, const std::string& name, const std::string& text) {
  const hsize_t size = text.size();
  H5::DSetCreatPropList properties;
  H5Pset_obj_track_times(properties.getId(), false);
  H5::DataSet set =
      parent.createDataSet(name, H5::PredType::NATIVE_UINT8, H5::DataSpace(1, &size), properties);
  if (size > 0) set.write(text.data(), H5::PredType::NATIVE_UINT8);
}

inline std::string read_bytes(const H5::Group& group, const std::string& name) {
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
inline herr_t refuse_external_link(hid_t, const char* name, const H5L_info_t* info, void* found) {
  if (info->type == H5L_TYPE_EXTERNAL || info->type >= H5L_TYPE_UD_MIN) {
    *static_cast<std::string*>(found) = name;
    return 1;
  }
  return 0;
}

inline void require_no_external_links(const H5::H5File& h5) {
  std::string found;
  if (H5Lvisit(h5.getId(), H5_INDEX_NAME, H5_ITER_NATIVE, refuse_external_link, &found) < 0)
    throw Error("cannot list the file's objects");
  if (!found.empty())
    throw Error("\"" + found + "\" is an external link (refused: a bake holds its data)");
}

inline void write_matrix(H5::Group& group, const std::string& name, const MatrixXfRow& m) {
  write_array(group, name, m.data(), m.rows(), m.cols());
}

// The same dataset as write_matrix, filled chunk by chunk from `rows`.
inline void write_streamed(H5::Group& group, const std::string& name,
                           const BakeData::StreamedRows& rows) {
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
inline BakeData::StreamedRows rows_of_file(const TransferSignal& signal) {
  BakeData::StreamedRows rows;
  rows.rows = signal.vertices();
  rows.cols = signal.dimension();
  rows.read = [&signal](Eigen::Index first, Eigen::Index count, MatrixXfRow& out) {
    out = signal.rows().middleRows(first, count);
    signal.release(first, first + count);
  };
  return rows;
}

// The float dataset `name` of `group`, checked as checked_dataset checks it,
// as rows read a block at a time when asked (so never whole in memory).
inline BakeData::StreamedRows dataset_rows(const H5::Group& group, const std::string& name) {
  hsize_t rows = 0, cols = 0;
  const H5::DataSet set = checked_dataset(group, name, H5T_FLOAT, rows, cols);
  BakeData::StreamedRows stream;
  stream.rows = Eigen::Index(rows), stream.cols = Eigen::Index(cols);
  stream.read = [set, name](Eigen::Index first, Eigen::Index count, MatrixXfRow& out) {
    reading_now = "dataset \"" + name + "\"";
    const H5::DataSpace space = set.getSpace();
    hsize_t dims[2];
    space.getSimpleExtentDims(dims);
    const hsize_t shape[2] = {hsize_t(count), dims[1]}, offset[2] = {hsize_t(first), 0};
    out.resize(count, Eigen::Index(dims[1]));
    H5::DataSpace file_space = set.getSpace();
    file_space.selectHyperslab(H5S_SELECT_SET, shape, offset);
    set.read(out.data(), h5_type<float>(), H5::DataSpace(2, shape), file_space);
  };
  return stream;
}

inline MatrixXfRow read_matrix(const H5::Group& group, const std::string& name) {
  hsize_t rows, cols;
  auto values = read_array<float>(group, name, rows, cols);
  return Eigen::Map<MatrixXfRow>(values.data(), rows, cols);
}

// Coordinates per item: an Eigen vector's size, or a std::array's.
template <class V>
constexpr int components_of() {
  if constexpr (requires { V::SizeAtCompileTime; })
    return int(V::SizeAtCompileTime);
  else
    return int(std::tuple_size_v<V>);
}

template <class V, class T>
inline void write_vectors(H5::Group& group, const std::string& name, const std::vector<V>& items) {
  constexpr int n = components_of<V>();
  std::vector<T> flat;
  flat.reserve(items.size() * n);
  for (const auto& item : items)
    for (int c = 0; c < n; ++c) flat.push_back(static_cast<T>(item[c]));
  write_array(group, name, flat.data(), items.size(), n);
}

template <class V, class T>
inline std::vector<V> read_vectors(const H5::Group& group, const std::string& name) {
  hsize_t rows, cols;
  constexpr int n = components_of<V>();
  auto flat = read_array<T>(group, name, rows, cols);
  if (cols != n)
    throw Error("dataset \"" + name + "\" must have " + std::to_string(n) + " columns");
  std::vector<V> items(rows);
  for (hsize_t r = 0; r < rows; ++r)
    for (int c = 0; c < n; ++c) items[r][c] = flat[r * n + c];
  return items;
}

inline void write_plugin(H5::H5Object& object, const std::string& prefix, const PluginRecord& p) {
  write_text(object, prefix + "_plugin", p.name);
  write_text(object, prefix + "_version", p.version);
  write_text(object, prefix + "_parameters", p.parameters);
}

inline PluginRecord read_plugin(const H5::H5Object& object, const std::string& prefix) {
  return {read_text(object, prefix + "_plugin"), read_text(object, prefix + "_version"),
          read_text(object, prefix + "_parameters")};
}

}  // namespace prt::bake_hdf5
