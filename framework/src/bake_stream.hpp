// A bake's fields as a byte stream from the process that parses the file
// (libhdf5, which may be fed a crafted file) to the one that uses it: every
// field is a frame (tag, shape, element size, bytes) that the receiver checks
// against what it expects and against a byte budget before it allocates.
// bake_fields lists the fields once, for both directions.
#pragma once
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

#include "prt/bake_file.hpp"
#include "prt/error.hpp"

namespace prt::bake_stream {

// The parse's own refusal ("FILE: bad bake file: ..."), passed on as it is.
struct ParseRefused : Error {
  using Error::Error;
};

// The sender: the child that read the file.
class Out {
 public:
  explicit Out(int fd) : fd_(fd) {}
  // Rows of the transfer and of its direct part, read from the file a block
  // at a time as they are sent (the sender never holds them whole); unset:
  // the signal's own rows.
  BakeData::StreamedRows transfer_rows, direct_rows;

  void operator()(const std::string& text) { frame(text.size(), 1, 1, text.data()); }
  template <class T>
  requires std::is_arithmetic_v<T>
  void operator()(const T& value) {
    const double number = static_cast<double>(value);
    frame(1, 1, sizeof number, &number);
  }
  template <class T>
  requires std::is_trivially_copyable_v<T>
  void operator()(const std::vector<T>& values) {
    frame(values.size(), 1, sizeof(T), values.data());
  }
  template <class T, std::size_t N>
  void operator()(const std::array<T, N>& values) {
    for (const T& value : values) (*this)(value);
  }
  void operator()(const Eigen::Vector3f& v) { frame(1, 3, sizeof(float), v.data()); }
  void operator()(const std::vector<Eigen::Vector3f>& v) {
    frame(v.size(), 3, sizeof(float), v.data());
  }
  void operator()(const std::vector<Eigen::Vector2f>& v) {
    frame(v.size(), 2, sizeof(float), v.data());
  }
  void operator()(const MatrixXfRow& m) { frame(m.rows(), m.cols(), sizeof(float), m.data()); }
  void operator()(const Eigen::MatrixXd& m) { frame(m.rows(), m.cols(), sizeof(double), m.data()); }
  void operator()(const std::vector<MatrixXfRow>& blocks);
  void operator()(const std::map<std::string, double>& values);
  void operator()(const std::map<std::string, Eigen::MatrixXd>& values);
  // A transfer's rows: their shape, then blocks of rows.
  void rows(const TransferSignal& signal, bool direct);

  // The stream's end, or the one message that says why it ends early.
  void end();
  void fail(const std::string& message);

 private:
  void frame(std::uint64_t rows, std::uint64_t cols, std::uint32_t element_bytes, const void* data,
             char tag = 'f');
  void bytes(const void* data, std::size_t size);
  int fd_;
};

// The receiver: checks every frame before it allocates for it.
class In {
 public:
  // `byte_limit`: the most bytes all frames may hold together (a parse of
  // a file yields no more values than the file stores). `reading`: where a
  // transfer too large for the memory budget goes (prt::ReadOptions).
  // `idle_seconds` (> 0): the longest wait for the sender's next bytes.
  // `data`: the bake being read, whose receivers (read before the rows) say
  // how many rows the transfer has.
  In(int fd, double byte_limit, const ReadOptions& reading, const BakeData& data,
     double idle_seconds = 0)
      : fd_(fd),
        left_(byte_limit),
        entries_left_(byte_limit / 4),
        idle_seconds_(idle_seconds),
        reading_(reading),
        data_(data) {}

  void operator()(std::string& text);
  template <class T>
  requires std::is_arithmetic_v<T>
  void operator()(T& value) {
    double number = 0;
    expect(1, 1, sizeof number, &number);
    value = number_as<T>(number);
  }
  template <class T>
  requires std::is_trivially_copyable_v<T>
  void operator()(std::vector<T>& values) {
    const Shape shape = header(sizeof(T));
    if (shape.cols != 1) refuse("a list with " + std::to_string(shape.cols) + " columns");
    values.resize(shape.rows);
    payload(values.data(), shape);
  }
  template <class T, std::size_t N>
  void operator()(std::array<T, N>& values) {
    for (T& value : values) (*this)(value);
  }
  void operator()(Eigen::Vector3f& v) { expect(1, 3, sizeof(float), v.data()); }
  void operator()(std::vector<Eigen::Vector3f>& v);
  void operator()(std::vector<Eigen::Vector2f>& v);
  void operator()(MatrixXfRow& m);
  void operator()(Eigen::MatrixXd& m);
  void operator()(std::vector<MatrixXfRow>& blocks);
  void operator()(std::map<std::string, double>& values);
  void operator()(std::map<std::string, Eigen::MatrixXd>& values);
  void rows(TransferSignal& signal, bool direct);
  void end();

 private:
  struct Shape {
    std::uint64_t rows = 0, cols = 0;
    std::uint32_t element_bytes = 0;
    double bytes() const { return double(rows) * double(cols) * double(element_bytes); }
  };
  Shape header(std::uint32_t element_bytes, char tag = 'f');
  void payload(void* data, const Shape& shape);
  void expect(std::uint64_t rows, std::uint64_t cols, std::uint32_t element_bytes, void* data);
  std::size_t count(const char* what);
  template <class T>
  T number_as(double number) {
    if constexpr (std::is_same_v<T, bool>) return number != 0;
    if constexpr (std::is_integral_v<T>) {
      if (!(number >= double(std::numeric_limits<T>::min()) &&
            number <= double(std::numeric_limits<T>::max())))
        refuse("a count out of range");
    }
    return static_cast<T>(number);
  }
  [[noreturn]] void refuse(const std::string& what) const;
  void read_exactly(void* data, std::size_t size);

  int fd_;
  double left_;
  // Entries of lists (clusters' blocks, metrics, states): the file stores
  // at least 4 bytes for each (a cluster's component count), so all lists
  // together have at most a quarter of its bytes.
  double entries_left_;
  double idle_seconds_;
  const ReadOptions reading_;  // a copy: callers may pass a temporary
  const BakeData& data_;
};

// Every field of a bake, in stream order, for Out and In alike.
template <class Io, class Data>
void bake_fields(Io& io, Data& d) {
  io(d.scene_file), io(d.scene_text), io(d.transport);
  for (auto* plugin : {&d.basis, &d.compressor, &d.exit})
    io(plugin->name), io(plugin->version), io(plugin->parameters);
  io(d.mesh.positions), io(d.mesh.normals), io(d.mesh.triangles);
  io(d.receivers.kind), io(d.receivers.grid.origin), io(d.receivers.grid.spacing);
  io(d.receivers.grid.counts), io(d.receivers.valid);
  io(d.mesh.uvs), io(d.receivers.atlas.width), io(d.receivers.atlas.height);
  io(d.receivers.atlas.texels), io(d.receivers.points.positions), io(d.receivers.points.normals);
  io(d.albedo), io(d.material), io(d.bounces), io(d.subsurface);
  io(d.transfer.kind), io(d.transfer.exit_rows), io(d.transfer.channel_groups);
  io(d.transfer.group_of_channel);
  io.rows(d.transfer, false);
  io.rows(d.direct, true);
  auto& c = d.compressed;
  io(c.compressor), io(c.dimension), io(c.components), io(c.cluster_of_vertex);
  io(c.weights), io(c.means), io(c.representatives), io(c.supercluster_of_cluster);
  io(c.weight_index);
  io(d.basis_state.matrices), io(d.exit_state.matrices), io(d.metrics);
  io.end();
}

}  // namespace prt::bake_stream
