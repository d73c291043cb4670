#include "bake_stream.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "child_process.hpp"
#include "prt/error.hpp"
#include "prt/memory.hpp"
#include "prt/output_file.hpp"
#include "prt/row_file.hpp"

namespace prt::bake_stream {

namespace {

constexpr std::size_t kBlockBytes = 8 << 20;  // rows of a transfer are sent in blocks of ~8 MB
constexpr std::size_t kMaxMessage = 1 << 16;  // an error frame's text

Eigen::Index block_rows(Eigen::Index cols) {
  return std::max<Eigen::Index>(1,
                                Eigen::Index(kBlockBytes / (4 * std::max<Eigen::Index>(cols, 1))));
}

}  // namespace

// ---- sender ----

void Out::bytes(const void* data, std::size_t size) {
  if (size > 0 && write_fully(fd_, data, size) != 0) throw Error("the bake's reader is gone");
}

void Out::frame(std::uint64_t rows, std::uint64_t cols, std::uint32_t element_bytes,
                const void* data, char tag) {
  bytes(&tag, 1);
  bytes(&rows, sizeof rows);
  bytes(&cols, sizeof cols);
  bytes(&element_bytes, sizeof element_bytes);
  if (data) bytes(data, std::size_t(rows * cols * element_bytes));
}

void Out::operator()(const std::vector<MatrixXfRow>& blocks) {
  (*this)(blocks.size());
  for (const auto& block : blocks) (*this)(block);
}

void Out::operator()(const std::map<std::string, double>& values) {
  (*this)(values.size());
  for (const auto& [name, value] : values) (*this)(name), (*this)(value);
}

void Out::operator()(const std::map<std::string, Eigen::MatrixXd>& values) {
  (*this)(values.size());
  for (const auto& [name, value] : values) (*this)(name), (*this)(value);
}

void Out::rows(const TransferSignal& signal, bool direct) {
  const BakeData::StreamedRows& source = direct ? direct_rows : transfer_rows;
  const Eigen::Index rows = source.read ? source.rows : signal.vertices(),
                     cols = source.read ? source.cols : signal.dimension();
  frame(std::uint64_t(rows), std::uint64_t(cols), 4, nullptr, 'r');
  MatrixXfRow block;
  for (Eigen::Index first = 0, step = block_rows(cols); first < rows; first += step) {
    const Eigen::Index count = std::min(step, rows - first);
    if (source.read)
      source.read(first, count, block);
    else
      block = signal.rows().middleRows(first, count);
    (*this)(block);
  }
}

void Out::end() {
  frame(0, 0, 0, nullptr, 'z');
}

void Out::fail(const std::string& message) {
  const std::string text = message.substr(0, kMaxMessage);
  frame(text.size(), 1, 1, text.data(), 'e');
}

// ---- receiver ----

void In::refuse(const std::string& what) const {
  throw Error("the process that parsed the file sent " + what);
}

void In::read_exactly(void* data, std::size_t size) {
  read_from_child(fd_, data, size, idle_seconds_);
}

In::Shape In::header(std::uint32_t element_bytes, char expected) {
  char tag = 0;
  Shape shape;
  read_exactly(&tag, 1);
  read_exactly(&shape.rows, sizeof shape.rows);
  read_exactly(&shape.cols, sizeof shape.cols);
  read_exactly(&shape.element_bytes, sizeof shape.element_bytes);
  if (tag == 'e') {  // the parse failed: its message is the answer
    if (shape.cols != 1 || shape.element_bytes != 1 || shape.rows > kMaxMessage)
      refuse("a malformed error message");
    std::string message(shape.rows, '\0');
    read_exactly(message.data(), message.size());
    throw ParseRefused(message);
  }
  if (tag != expected) refuse("its values out of order");
  if (shape.element_bytes != element_bytes) refuse("a value of the wrong type");
  if (shape.bytes() > left_) refuse("more values than the file stores");
  if (tag == 'f') left_ -= shape.bytes();
  return shape;
}

void In::payload(void* data, const Shape& shape) {
  read_exactly(data, std::size_t(shape.bytes()));
}

void In::expect(std::uint64_t rows, std::uint64_t cols, std::uint32_t element_bytes, void* data) {
  const Shape shape = header(element_bytes);
  if (shape.rows != rows || shape.cols != cols) refuse("a value of the wrong shape");
  payload(data, shape);
}

std::size_t In::count(const char* what) {
  double number = 0;
  expect(1, 1, sizeof number, &number);
  if (!(number >= 0 && number <= entries_left_)) refuse(std::string("a bad count of ") + what);
  entries_left_ -= number;
  return std::size_t(number);
}

void In::operator()(std::string& text) {
  const Shape shape = header(1);
  if (shape.cols != 1) refuse("a text of the wrong shape");
  text.assign(shape.rows, '\0');
  payload(text.data(), shape);
}

void In::operator()(std::vector<Eigen::Vector3f>& v) {
  const Shape shape = header(sizeof(float));
  if (shape.cols != 3) refuse("vectors of " + std::to_string(shape.cols) + " coordinates");
  v.resize(shape.rows);
  payload(v.data(), shape);
}

void In::operator()(std::vector<Eigen::Vector2f>& v) {
  const Shape shape = header(sizeof(float));
  if (shape.cols != 2) refuse("texture coordinates of " + std::to_string(shape.cols) + " values");
  v.resize(shape.rows);
  payload(v.data(), shape);
}

void In::operator()(MatrixXfRow& m) {
  const Shape shape = header(sizeof(float));
  m.resize(Eigen::Index(shape.rows), Eigen::Index(shape.cols));
  payload(m.data(), shape);
}

void In::operator()(Eigen::MatrixXd& m) {
  const Shape shape = header(sizeof(double));
  m.resize(Eigen::Index(shape.rows), Eigen::Index(shape.cols));
  payload(m.data(), shape);
}

void In::operator()(std::vector<MatrixXfRow>& blocks) {
  blocks.resize(count("blocks"));
  for (auto& block : blocks) (*this)(block);
}

void In::operator()(std::map<std::string, double>& values) {
  for (std::size_t i = 0, n = count("values"); i < n; ++i) {
    std::string name;
    (*this)(name);
    (*this)(values[name]);
  }
}

void In::operator()(std::map<std::string, Eigen::MatrixXd>& values) {
  for (std::size_t i = 0, n = count("matrices"); i < n; ++i) {
    std::string name;
    (*this)(name);
    (*this)(values[name]);
  }
}

// The rows go to memory, or to a row file beside the memory budget when
// they would not fit in it (as ReadOptions asks); each block is checked.
void In::rows(TransferSignal& signal, bool direct) {
  const Shape shape = header(4, 'r');
  const auto rows = Eigen::Index(shape.rows), cols = Eigen::Index(shape.cols);
  // Known before any row is read: one row per receiver (a direct part may be absent).
  const auto receivers = Eigen::Index(data_.receiver_count());
  if (rows != receivers && !(direct && rows == 0 && cols == 0))
    throw Error("the " + std::string(direct ? "direct transfer" : "transfer") + " has " +
                std::to_string(rows) + " rows for " + std::to_string(receivers) + " " +
                (data_.receivers.at_vertices() ? "vertices" : data_.receivers.kind));
  const double beside = kMeshBytesPerVertex * double(data_.mesh.vertex_count());
  std::shared_ptr<RowFile> file;
  if (!direct && reading_.memory_budget > 0 && shape.bytes() + beside > reading_.memory_budget)
    file = RowFile::create(reading_.rows_folder, rows, cols);
  else
    signal.coefficients.resize(rows, cols);
  const char* name = direct ? "direct_coefficients" : "coefficients";
  MatrixXfRow block;
  for (Eigen::Index first = 0; first < rows; first += block.rows()) {
    (*this)(block);
    if (block.cols() != cols || block.rows() < 1 || block.rows() > rows - first)
      refuse(std::string("rows of \"") + name + "\" that do not fit its shape");
    for (Eigen::Index r = 0; r < block.rows(); ++r)
      if (!block.row(r).allFinite())
        throw Error("dataset \"" + std::string(name) + "\" has a NaN or infinite value at row " +
                    std::to_string(first + r));
    if (file)
      file->write(first, block);
    else
      signal.coefficients.middleRows(first, block.rows()) = block;
  }
  if (file) file->map(), signal.file = std::move(file);
}

void In::end() {
  const Shape shape = header(0, 'z');
  if (shape.rows != 0 || shape.cols != 0) refuse("data past its end");
}

}  // namespace prt::bake_stream
