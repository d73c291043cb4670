#include "mesh_file_check.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "prt/error.hpp"

namespace prt {
namespace fs = std::filesystem;

namespace {

constexpr std::uint64_t kMaxHeaderBytes = 1 << 20;
constexpr std::uint64_t kMaxElements = 1ull << 31;  // indices are 32-bit

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

bool is_blank_or_comment(const std::string& line) {
  const auto at = line.find_first_not_of(" \t\r");
  return at == std::string::npos || line[at] == '#';
}

// Lines after the current position that hold data (not blank, not comments).
std::uint64_t count_data_lines(std::istream& in) {
  std::uint64_t count = 0;
  for (std::string line; std::getline(in, line);)
    if (!is_blank_or_comment(line)) ++count;
  return count;
}

class Checker {
 public:
  explicit Checker(const fs::path& file) : file_(file), in_(file, std::ios::binary) {
    std::error_code error;
    size_ = fs::file_size(file, error);
    if (!in_ || error) fail("cannot read the mesh file");
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw Error(file_.string() + (line_ ? ":" + std::to_string(line_) : "") + ": " + what);
  }

  // The next line that holds data; false at the end of the file.
  bool next_data_line(std::string& line) {
    while (std::getline(in_, line)) {
      ++line_;
      if (static_cast<std::uint64_t>(in_.tellg()) > kMaxHeaderBytes && in_.tellg() >= 0)
        fail("no complete header within the first 1 MiB");
      if (!is_blank_or_comment(line)) return true;
    }
    return false;
  }

  std::uint64_t count(const std::string& token, const char* what) const {
    if (token.empty() || token.find_first_not_of("0123456789") != std::string::npos)
      fail(std::string("the header's ") + what + " \"" + token + "\" is not a count");
    if (token.size() > 12 || std::stoull(token) > kMaxElements)
      fail(std::string("the header declares ") + token + " " + what + "; at most " +
           std::to_string(kMaxElements) + " are supported");
    return std::stoull(token);
  }

  std::uint64_t remaining_bytes() {
    const auto at = in_.tellg();
    return at < 0 ? 0 : size_ - std::min<std::uint64_t>(size_, static_cast<std::uint64_t>(at));
  }

  // Refuses a body that cannot hold `elements` of at least `bytes_each` bytes.
  void require_room(long double needed, const std::string& what) {
    const std::uint64_t room = remaining_bytes();
    if (needed > static_cast<long double>(room))
      fail("the header declares " + what + ", which need at least " +
           std::to_string(static_cast<std::uint64_t>(std::min<long double>(needed, 1e19L))) +
           " bytes, but only " + std::to_string(room) + " follow (truncated or damaged file)");
  }

  void require_lines(std::uint64_t expected, const std::string& what) {
    const std::uint64_t found = count_data_lines(in_);
    if (found < expected)
      fail("truncated: the header declares " + what + " (" + std::to_string(expected) +
           " lines), but the file holds " + std::to_string(found));
  }

  DeclaredMeshSize off();
  DeclaredMeshSize ply();
  DeclaredMeshSize stl();

 private:
  fs::path file_;
  std::ifstream in_;
  std::uint64_t size_ = 0;
  std::uint64_t line_ = 0;
};

DeclaredMeshSize Checker::off() {
  std::string line;
  if (!next_data_line(line)) fail("empty OFF file");
  std::istringstream tokens(line);
  std::string keyword;
  tokens >> keyword;
  const std::string k = lower(keyword);
  if (k.size() < 3 || k.compare(k.size() - 3, 3, "off") != 0) fail("not an OFF file (no OFF keyword)");
  std::vector<std::string> rest;
  for (std::string t; tokens >> t;) rest.push_back(t);
  const bool binary = !rest.empty() && lower(rest[0]) == "binary";
  if (binary) fail("binary OFF files are not supported; convert to ASCII OFF or PLY");
  const std::string prefix = keyword.substr(0, keyword.size() - 3);
  if (prefix.find_first_of("4n") != std::string::npos)
    fail("4-D and n-D OFF variants are not supported");
  if (rest.empty()) {
    if (!next_data_line(line)) fail("the OFF header has no vertex and face counts");
    std::istringstream counts(line);
    for (std::string t; counts >> t;) rest.push_back(t);
  }
  if (rest.size() < 2) fail("the OFF header needs vertex and face counts");
  DeclaredMeshSize size{true, count(rest[0], "vertices"), count(rest[1], "faces")};
  // "x y z" needs 6 bytes with its newline, "3 a b c" 8.
  require_room(6.0L * size.vertices + 8.0L * size.faces,
               std::to_string(size.vertices) + " vertices and " + std::to_string(size.faces) +
                   " faces");
  require_lines(size.vertices + size.faces,
                std::to_string(size.vertices) + " vertices and " + std::to_string(size.faces) +
                    " faces");
  return size;
}

DeclaredMeshSize Checker::ply() {
  static const std::map<std::string, int> type_bytes{
      {"char", 1},  {"int8", 1},   {"uchar", 1},   {"uint8", 1},   {"short", 2},
      {"int16", 2}, {"ushort", 2}, {"uint16", 2},  {"int", 4},     {"int32", 4},
      {"uint", 4},  {"uint32", 4}, {"float", 4},   {"float32", 4}, {"double", 8},
      {"float64", 8}};
  struct Element {
    std::string name;
    std::uint64_t count = 0;
    long double min_bytes = 0;
  };
  std::vector<Element> elements;
  std::string line, format;
  bool ended = false;
  while (!ended && std::getline(in_, line)) {
    ++line_;
    if (static_cast<std::uint64_t>(in_.tellg()) > kMaxHeaderBytes)
      fail("no end_header within the first 1 MiB");
    std::istringstream tokens(line);
    std::string keyword;
    tokens >> keyword;
    if (line_ == 1) {
      if (keyword != "ply") fail("not a PLY file (no \"ply\" line)");
      continue;
    }
    if (keyword == "format") {
      tokens >> format;
    } else if (keyword == "element") {
      std::string name, n;
      tokens >> name >> n;
      elements.push_back({name, count(n, ("\"" + name + "\" elements").c_str()), 0});
    } else if (keyword == "property") {
      if (elements.empty()) fail("a property before any element");
      std::string type;
      tokens >> type;
      if (type == "list") {
        std::string count_type, item_type;
        tokens >> count_type >> item_type;
        if (!type_bytes.count(count_type) || !type_bytes.count(item_type))
          fail("unknown PLY property type in \"" + line + "\"");
        // A face lists at least 3 vertices; other lists may be empty.
        const int items = elements.back().name == "face" ? 3 : 0;
        elements.back().min_bytes += type_bytes.at(count_type) + items * type_bytes.at(item_type);
      } else {
        if (!type_bytes.count(type)) fail("unknown PLY property type \"" + type + "\"");
        elements.back().min_bytes += type_bytes.at(type);
      }
    } else if (keyword == "end_header") {
      ended = true;
    } else if (keyword != "comment" && keyword != "obj_info" && !keyword.empty()) {
      fail("unexpected PLY header line \"" + line.substr(0, 60) + "\"");
    }
  }
  if (!ended) fail("no end_header: the PLY header is incomplete");
  if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian")
    fail("unknown PLY format \"" + format + "\"");
  DeclaredMeshSize size{true, 0, 0};
  long double needed = 0;
  std::uint64_t lines = 0;
  for (const auto& e : elements) {
    if (e.name == "vertex") size.vertices = e.count;
    if (e.name == "face") size.faces = e.count;
    needed += format == "ascii" ? 2.0L * e.count : e.min_bytes * e.count;
    lines += e.count;
  }
  const std::string what = std::to_string(size.vertices) + " vertices and " +
                           std::to_string(size.faces) + " faces";
  require_room(needed, what);
  if (format == "ascii") require_lines(lines, what);
  return size;
}

DeclaredMeshSize Checker::stl() {
  char head[84] = {};
  in_.read(head, sizeof head);
  const auto got = static_cast<std::uint64_t>(in_.gcount());
  std::uint32_t triangles = 0;
  if (got == sizeof head) std::memcpy(&triangles, head + 80, 4);
  if (got == sizeof head && size_ == 84 + 50ull * triangles) return {true, 0, triangles};
  if (got < 5 || lower(std::string(head, 5)) != "solid")
    fail("binary STL of " + std::to_string(size_) + " bytes, but its header declares " +
         std::to_string(triangles) + " triangles (" + std::to_string(84 + 50ull * triangles) +
         " bytes): truncated or damaged");
  // ASCII: every facet closed, and the solid too.
  in_.clear();
  in_.seekg(0);
  std::uint64_t opened = 0, closed = 0;
  bool solid_closed = false;
  for (std::string token; in_ >> token;) {
    const std::string t = lower(token);
    if (t == "facet") ++opened, solid_closed = false;
    if (t == "endfacet") ++closed;
    if (t == "endsolid") solid_closed = true;
  }
  if (!solid_closed) fail("truncated ASCII STL: no closing \"endsolid\"");
  if (opened != closed)
    fail("truncated ASCII STL: " + std::to_string(opened) + " facets opened, " +
         std::to_string(closed) + " closed");
  return {true, 0, closed};
}

}  // namespace

DeclaredMeshSize check_mesh_file(const fs::path& file) {
  const std::string extension = lower(file.extension().string());
  Checker checker(file);
  if (extension == ".off") return checker.off();
  if (extension == ".ply") return checker.ply();
  if (extension == ".stl" || extension == ".stla" || extension == ".stlb") return checker.stl();
  return {};
}

}  // namespace prt
