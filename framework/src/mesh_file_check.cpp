#include "mesh_file_check.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
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

// A PLY element as its header declares it.
struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  long double min_bytes = 0;
  std::vector<std::string> scalars;  // scalar property names
  int lists = 0;
  std::vector<bool> is_list;  // each property in order: a list or a scalar
};

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
  bool next_data_line(std::string& line, bool in_header = true) {
    while (std::getline(in_, line)) {
      ++line_;
      if (in_header && static_cast<std::uint64_t>(in_.tellg()) > kMaxHeaderBytes &&
          in_.tellg() >= 0)
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

  // Text readers and this checker must tokenise alike: no control bytes but
  // tab, CR and LF, no non-ASCII bytes outside '#' comments. Reads the whole
  // file, then returns to where it was.
  void require_plain_text() {
    const auto start = in_.tellg();
    std::uint64_t line = 1;
    bool comment = false;
    for (int c; (c = in_.get()) != std::char_traits<char>::eof();) {
      if (c == '\n') {
        ++line, comment = false;
        continue;
      }
      if (c == '#') comment = true;
      if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7f || (c >= 0x80 && !comment)) {
        line_ = line;
        fail("unexpected byte 0x" + std::string(1, "0123456789abcdef"[c >> 4]) +
             std::string(1, "0123456789abcdef"[c & 15]) + " in a text mesh");
      }
    }
    in_.clear();
    in_.seekg(start);
  }

  static bool is_number(const std::string& t) {
    char* end = nullptr;
    const double value = std::strtod(t.c_str(), &end);
    return end && *end == '\0' && end != t.c_str() && std::isfinite(value);
  }

  DeclaredMeshSize off();
  void off_body(const DeclaredMeshSize& size);
  DeclaredMeshSize obj();
  DeclaredMeshSize ply();
  // The header, checked strictly line by line; returns the format.
  std::string ply_header(std::vector<PlyElement>& elements);
  void ply_property(const std::vector<std::string>& tokens, const std::string& line,
                    PlyElement& element);
  // ASCII: one line per element, every token a number, each list's count
  // within the line.
  void ply_ascii_body(const std::vector<PlyElement>& elements, const std::string& what);
  DeclaredMeshSize stl();

 private:
  fs::path file_;
  std::ifstream in_;
  std::uint64_t size_ = 0;
  std::uint64_t line_ = 0;
};

DeclaredMeshSize Checker::off() {
  require_plain_text();
  std::string line;
  if (!next_data_line(line)) fail("empty OFF file");
  std::istringstream tokens(line);
  std::string keyword;
  tokens >> keyword;
  const std::string k = lower(keyword);
  if (k.size() < 3 || k.compare(k.size() - 3, 3, "off") != 0)
    fail("not an OFF file (no OFF keyword)");
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
  // "nv nf [ne]" and nothing else: OpenMesh's reader loops on some junk here.
  if (rest.size() < 2 || rest.size() > 3)
    fail("the OFF header needs vertex, face and edge counts (\"nv nf ne\")");
  DeclaredMeshSize size{true, count(rest[0], "vertices"), count(rest[1], "faces")};
  if (rest.size() == 3) count(rest[2], "edges");
  if (size.vertices < 3 || size.faces < 1)
    fail("the OFF header declares " + std::to_string(size.vertices) + " vertices and " +
         std::to_string(size.faces) + " faces: no surface");
  // "x y z" needs 6 bytes with its newline, "3 a b c" 8.
  require_room(
      6.0L * size.vertices + 8.0L * size.faces,
      std::to_string(size.vertices) + " vertices and " + std::to_string(size.faces) + " faces");
  off_body(size);
  return size;
}

// Line by line (OpenMesh reserves what a face line's count says): a vertex
// line has 3 coordinates or more, a face line "k i_1 .. i_k" with 3 <= k.
void Checker::off_body(const DeclaredMeshSize& size) {
  std::string line;
  std::uint64_t vertices = 0, faces = 0;
  while (faces < size.faces && next_data_line(line, false)) {
    std::istringstream stream(line);
    std::vector<std::string> tokens;
    for (std::string t; stream >> t;) tokens.push_back(t);
    if (tokens.empty()) continue;  // only form feeds or vertical tabs
    if (vertices < size.vertices) {
      if (tokens.size() < 3) fail("a vertex needs 3 coordinates");
      ++vertices;
      continue;
    }
    const std::string& k = tokens[0];
    if (k.find_first_not_of("0123456789") != std::string::npos || k.size() > 6 ||
        std::stoul(k) < 3 || std::stoul(k) > tokens.size() - 1)
      fail("a face must be \"k i_1 ... i_k\" with k >= 3 vertex indices, not \"" +
           line.substr(0, 40) + "\"");
    // Each index a vertex of the file: OpenMesh's stream fails on a number
    // beyond an int and then reads the next counts from a failed stream
    // (a 182-byte file grew to 8 GB).
    for (std::size_t i = 1; i <= std::stoul(k); ++i) {
      const std::string& index = tokens[i];
      if (index.find_first_not_of("0123456789") != std::string::npos || index.size() > 10 ||
          std::stoull(index) >= size.vertices)
        fail("face " + std::to_string(faces + 1) + " uses vertex index \"" + index.substr(0, 20) +
             "\", but the file declares " + std::to_string(size.vertices) + " vertices");
    }
    ++faces;
  }
  if (faces < size.faces)
    fail("truncated: the header declares " + std::to_string(size.vertices) + " vertices and " +
         std::to_string(size.faces) + " faces, but the file ends after " +
         std::to_string(vertices) + " vertices and " + std::to_string(faces) + " faces");
}

namespace {
const std::map<std::string, int> kPlyTypeBytes{
    {"char", 1},   {"int8", 1},    {"uchar", 1},  {"uint8", 1},  {"short", 2}, {"int16", 2},
    {"ushort", 2}, {"uint16", 2},  {"int", 4},    {"int32", 4},  {"uint", 4},  {"uint32", 4},
    {"float", 4},  {"float32", 4}, {"double", 8}, {"float64", 8}};
}  // namespace

void Checker::ply_property(const std::vector<std::string>& tokens, const std::string& line,
                           PlyElement& e) {
  if (tokens.size() == 5 && tokens[1] == "list") {
    if (!kPlyTypeBytes.count(tokens[2]) || !kPlyTypeBytes.count(tokens[3]))
      fail("unknown PLY property type in \"" + line.substr(0, 60) + "\"");
    // A face lists at least 3 vertices; other lists may be empty.
    const int items = e.name == "face" ? 3 : 0;
    e.min_bytes += kPlyTypeBytes.at(tokens[2]) + items * kPlyTypeBytes.at(tokens[3]);
    ++e.lists;
    e.is_list.push_back(true);
  } else if (tokens.size() == 3 && tokens[1] != "list") {
    if (!kPlyTypeBytes.count(tokens[1])) fail("unknown PLY property type \"" + tokens[1] + "\"");
    e.min_bytes += kPlyTypeBytes.at(tokens[1]);
    e.scalars.push_back(tokens[2]);
    e.is_list.push_back(false);
  } else {
    fail("malformed PLY header line \"" + line.substr(0, 60) + "\"");
  }
}

std::string Checker::ply_header(std::vector<PlyElement>& elements) {
  std::string line, format;
  bool ended = false;
  // OpenMesh's PLY reader loops forever on some malformed headers.
  while (!ended && std::getline(in_, line)) {
    ++line_;
    if (static_cast<std::uint64_t>(in_.tellg()) > kMaxHeaderBytes)
      fail("no end_header within the first 1 MiB");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream stream(line);
    std::vector<std::string> tokens;
    for (std::string t; stream >> t;) tokens.push_back(t);
    const std::string keyword = tokens.empty() ? "" : tokens[0];
    auto malformed = [&] { fail("malformed PLY header line \"" + line.substr(0, 60) + "\""); };
    if (line_ == 1) {
      if (line != "ply") fail("not a PLY file (no \"ply\" line)");
      continue;
    }
    if (keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "format") {
      if (tokens.size() != 3 || tokens[2] != "1.0" || !format.empty() || !elements.empty())
        malformed();
      format = tokens[1];
    } else if (keyword == "element") {
      if (tokens.size() != 3) malformed();
      for (const auto& e : elements)
        if (e.name == tokens[1]) fail("PLY element \"" + tokens[1] + "\" declared twice");
      elements.push_back({tokens[1], count(tokens[2], ("\"" + tokens[1] + "\" elements").c_str())});
    } else if (keyword == "property") {
      if (elements.empty()) fail("a property before any element");
      ply_property(tokens, line, elements.back());
    } else if (keyword == "end_header") {
      if (tokens.size() != 1) malformed();
      ended = true;
    } else {
      fail("unexpected PLY header line \"" + line.substr(0, 60) + "\"");
    }
  }
  if (!ended) fail("no end_header: the PLY header is incomplete");
  if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian")
    fail("unknown PLY format \"" + format + "\"");
  return format;
}

void Checker::ply_ascii_body(const std::vector<PlyElement>& elements, const std::string& what) {
  std::string line;
  for (const auto& e : elements)
    for (std::uint64_t k = 0; k < e.count; ++k) {
      if (!next_data_line(line, false))
        fail("truncated: the header declares " + what + ", but the file ends in the \"" + e.name +
             "\" elements");
      std::istringstream stream(line);
      std::vector<std::string> tokens;
      for (std::string t; stream >> t;) tokens.push_back(t);
      std::size_t at = 0;
      for (bool list : e.is_list) {
        if (at >= tokens.size() || !is_number(tokens[at]))
          fail("a \"" + e.name + "\" line needs a number for each property");
        if (!list) {
          ++at;
          continue;
        }
        const std::string& n = tokens[at];
        const bool whole = n.find_first_not_of("0123456789") == std::string::npos && n.size() < 6;
        const std::size_t items = whole ? std::stoul(n) : 0;
        if (!whole || (e.name == "face" && items < 3) || at + 1 + items > tokens.size())
          fail("a list in a \"" + e.name + "\" line must be \"k v_1 ... v_k\", not \"" +
               line.substr(0, 40) + "\"");
        for (std::size_t i = at + 1; i <= at + items; ++i)
          if (!is_number(tokens[i])) fail("a \"" + e.name + "\" line holds a non-number");
        at += 1 + items;
      }
    }
}

DeclaredMeshSize Checker::ply() {
  std::vector<PlyElement> elements;
  const std::string format = ply_header(elements);
  auto has = [](const std::vector<std::string>& names, const char* name) {
    return std::find(names.begin(), names.end(), name) != names.end();
  };
  if (elements.empty() || elements[0].name != "vertex" || !has(elements[0].scalars, "x") ||
      !has(elements[0].scalars, "y") || !has(elements[0].scalars, "z") || elements[0].lists)
    fail("the first PLY element must be \"vertex\" with scalar properties x, y and z");
  for (const auto& e : elements)
    if (e.name == "face" && (e.lists != 1 || e.min_bytes == 0))
      fail("the PLY element \"face\" must have one list property of vertex indices");
  DeclaredMeshSize size{true, 0, 0};
  long double needed = 0;
  for (const auto& e : elements) {
    if (e.name == "vertex") size.vertices = e.count;
    if (e.name == "face") size.faces = e.count;
    needed += format == "ascii" ? 2.0L * e.count : e.min_bytes * e.count;
  }
  const std::string what =
      std::to_string(size.vertices) + " vertices and " + std::to_string(size.faces) + " faces";
  require_room(needed, what);
  if (format != "ascii") return size;
  // OpenMesh reserves what a list's count says.
  require_plain_text();
  ply_ascii_body(elements, what);
  return size;
}

// OBJ declares no counts, and OpenMesh's reader asserts (aborts) on some
// malformed lines: every line is checked to be a known statement with
// numbers where numbers belong and face indices that refer to vertices.
DeclaredMeshSize Checker::obj() {
  std::uint64_t vertices = 0, texture = 0, normals = 0, faces = 0;
  std::string line;
  while (std::getline(in_, line)) {
    ++line_;
    std::istringstream stream(line);
    std::vector<std::string> tokens;
    for (std::string t; stream >> t;) tokens.push_back(t);
    if (tokens.empty() || tokens[0][0] == '#') continue;
    const std::string& keyword = tokens[0];
    static const char* names[] = {"o", "g", "s", "usemtl", "mtllib"};
    if (std::find(std::begin(names), std::end(names), keyword) != std::end(names)) continue;
    for (char c : line)
      if (static_cast<unsigned char>(c) >= 0x80 ||
          (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\r'))
        fail("unexpected byte in an OBJ statement");
    if (keyword == "v" || keyword == "vn" || keyword == "vt") {
      const std::size_t needed = keyword == "vt" ? 1 : 3;
      if (tokens.size() < needed + 1 || tokens.size() > 5 ||
          !std::all_of(tokens.begin() + 1, tokens.end(), is_number))
        fail("\"" + keyword + "\" needs " + std::to_string(needed) + " or more numbers");
      (keyword == "v" ? vertices : keyword == "vn" ? normals : texture)++;
    } else if (keyword == "f") {
      if (tokens.size() < 4) fail("a face needs 3 or more vertices");
      for (std::size_t k = 1; k < tokens.size(); ++k) {
        // i, i/t, i//n or i/t/n; negative indices count back from the end.
        std::istringstream parts(tokens[k]);
        std::string part;
        const std::uint64_t limits[3] = {vertices, texture, normals};
        for (int slot = 0; std::getline(parts, part, '/'); ++slot) {
          if (slot > 2 || (part.empty() && slot == 0))
            fail("malformed face vertex \"" + tokens[k] + "\"");
          if (part.empty()) continue;
          const std::string digits = part[0] == '-' ? part.substr(1) : part;
          if (digits.empty() || digits.size() > 10 ||
              digits.find_first_not_of("0123456789") != std::string::npos ||
              std::stoull(digits) == 0 || std::stoull(digits) > limits[slot])
            fail("face vertex \"" + tokens[k] + "\" refers to an element that does not exist");
        }
      }
      ++faces;
    } else if (keyword == "l" || keyword == "vp") {
      continue;
    } else {
      fail("unknown OBJ statement \"" + keyword.substr(0, 20) + "\"");
    }
  }
  if (vertices < 3 || faces < 1) fail("an OBJ mesh needs 3 vertices and a face");
  return {true, vertices, faces};
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
  std::uint64_t opened = 0, closed = 0, corners = 0;
  bool solid_closed = false;
  for (std::string token; in_ >> token;) {
    const std::string t = lower(token);
    if (t == "facet") ++opened, solid_closed = false, corners = 0;
    if (t == "vertex") ++corners;
    if (t == "endfacet") {
      ++closed;
      // A reader keeps three corners of a facet and drops the rest silently.
      if (corners != 3)
        fail("ASCII STL facet " + std::to_string(closed) + " has " + std::to_string(corners) +
             " vertices; a facet must have exactly 3");
    }
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
  if (extension == ".obj") return checker.obj();
  return {};
}

}  // namespace prt
