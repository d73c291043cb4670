// Receivers: where a bake computes transfer. Mesh vertices (the default:
// the transfer's rows are the mesh's vertices) or probes on a regular grid
// over the scene, each receiving light over the whole sphere. The bases,
// compressors and bake file are the same for both; only the rows differ.
#pragma once
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "prt/mesh.hpp"
#include "prt/texel_atlas.hpp"

namespace prt {

// A regular grid of probes: probe (x, y, z) sits at origin + spacing * (x, y, z),
// probe index x + counts[0] * (y + counts[1] * z).
struct ProbeGrid {
  Eigen::Vector3f origin{0, 0, 0};
  float spacing = 1;
  std::array<int, 3> counts{0, 0, 0};

  std::size_t count() const { return std::size_t(counts[0]) * counts[1] * counts[2]; }
  std::size_t index(int x, int y, int z) const {
    return std::size_t(x) + std::size_t(counts[0]) * (std::size_t(y) + std::size_t(counts[1]) * z);
  }
  Eigen::Vector3f position(std::size_t probe) const;
  // The 8 probes of the grid cell that holds `point` (clamped to the grid:
  // a point outside takes the nearest cell's face) and their trilinear
  // weights, which sum to 1. On a grid one probe thick along an axis, the
  // pairs along it are the same probe with half the weight each.
  void cell(const Eigen::Vector3f& point, std::array<std::uint32_t, 8>& probes,
            std::array<float, 8>& weights) const;
};

// A grid of the given spacing over the box [lo, hi]: as many probes along
// each axis as fit (at least one), centred in the box, so none sits on its
// faces (where a scene's outer surfaces are).
ProbeGrid probe_grid_over(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float spacing);

// Throws prt::Error unless the grid is finite, its spacing positive and its
// counts in range; `source` names it.
void check_probe_grid(const ProbeGrid& grid, const std::string& source);

struct Receivers {
  std::string kind = "vertices";  // "vertices", "texels" or "probes"
  ProbeGrid grid;                 // probes only
  TexelAtlas atlas;               // texels only: which texel each row is
  // probes only: 1 where the probe is usable, 0 where it sits inside
  // geometry (most of its rays hit back faces); one per probe.
  std::vector<std::uint8_t> valid;
  // probes and texels: one point per transfer row (positions; the texels'
  // surface normals, zero normals at probes; no triangles): what the bake
  // traces from, and what a compressor that clusters by position, or a
  // report of overdraw, is given instead of the scene's mesh.
  Mesh points;

  bool probes() const { return kind == "probes"; }
  bool texels() const { return kind == "texels"; }
  bool at_vertices() const { return kind == "vertices"; }
  // Texels of an atlas, with their surface points.
  static Receivers texels_of(TexelSamples samples);
  // Probes on `grid` with their validity; `points` made from the grid.
  static Receivers probes_on(const ProbeGrid& grid, std::vector<std::uint8_t> valid);
};

}  // namespace prt
