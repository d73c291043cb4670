// How much memory this process may use: for refusals made before the work
// that would run out (a bake's arrays, a subdivided mesh).
#pragma once
#include <string>

namespace prt {

// Memory this machine can give now (MemAvailable), in bytes, and no more than
// the address space this process's limit (ulimit -v) still leaves it.
double available_memory();

// The machine's memory, or the control group's limit when lower (a
// container, a Slurm job): what this process may really hold.
double physical_memory();

// The share of physical memory a bake's default budget takes.
constexpr double kDefaultMemoryFraction = 0.75;
// Bytes a bake holds per mesh vertex beside its transfer while it traces
// (the mesh, its adjacency and Embree's BVH; measured: docs/scale.md).
constexpr double kMeshBytesPerVertex = 400;

// Peak resident memory of this process so far (VmHWM), in bytes.
double peak_resident_bytes();

// "640 MB", "3.2 GB".
std::string gigabytes(double bytes);

}  // namespace prt
