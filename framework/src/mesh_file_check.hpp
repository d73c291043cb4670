// Checks a mesh file's declared sizes against the file before OpenMesh reads
// it: OpenMesh reserves what a header declares and reads a truncated file to
// its end, so a few bytes could cost gigabytes and minutes.
#pragma once
#include <cstdint>
#include <filesystem>

namespace prt {

struct DeclaredMeshSize {
  bool known = false;  // false for formats without declared counts (OBJ)
  std::uint64_t vertices = 0, faces = 0;
};

// Throws prt::Error naming the file (and line where it helps) when a header
// is malformed, declares more elements than the file can hold, or the body is
// truncated. Returns the declared counts, to compare with what was read.
DeclaredMeshSize check_mesh_file(const std::filesystem::path& file);

}  // namespace prt
