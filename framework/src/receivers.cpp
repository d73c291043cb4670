#include "prt/receivers.hpp"

#include <algorithm>
#include <cmath>

#include "prt/error.hpp"

namespace prt {

Eigen::Vector3f ProbeGrid::position(std::size_t probe) const {
  const std::size_t x = probe % std::size_t(counts[0]);
  const std::size_t y = (probe / std::size_t(counts[0])) % std::size_t(counts[1]);
  const std::size_t z = probe / (std::size_t(counts[0]) * std::size_t(counts[1]));
  return origin + spacing * Eigen::Vector3f(float(x), float(y), float(z));
}

void ProbeGrid::cell(const Eigen::Vector3f& point, std::array<std::uint32_t, 8>& probes,
                     std::array<float, 8>& weights) const {
  int lower[3];
  float t[3];
  for (int a = 0; a < 3; ++a) {
    const float at = (point[a] - origin[a]) / spacing;
    const int last = counts[a] - 1;
    // NaN and points outside clamp to the grid's faces.
    const float clamped = std::isfinite(at) ? std::clamp(at, 0.f, float(last)) : 0.f;
    lower[a] = std::min(int(std::floor(clamped)), std::max(last - 1, 0));
    t[a] = last > 0 ? clamped - float(lower[a]) : 0.5f;
  }
  for (int corner = 0; corner < 8; ++corner) {
    int at[3];
    float weight = 1;
    for (int a = 0; a < 3; ++a) {
      const int step = (corner >> a) & 1;
      at[a] = std::min(lower[a] + step, counts[a] - 1);
      weight *= step ? t[a] : 1 - t[a];
    }
    probes[std::size_t(corner)] = static_cast<std::uint32_t>(index(at[0], at[1], at[2]));
    weights[std::size_t(corner)] = weight;
  }
}

ProbeGrid probe_grid_over(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float spacing) {
  if (!(spacing > 0) || !std::isfinite(spacing))
    throw Error("probe spacing " + std::to_string(spacing) + " is not a positive number");
  ProbeGrid grid;
  grid.spacing = spacing;
  const Eigen::Vector3f centre = (lo + hi) / 2;
  for (int a = 0; a < 3; ++a) {
    const double extent = std::max(0.0, double(hi[a]) - double(lo[a]));
    const double along = std::max(1.0, std::ceil(extent / spacing));
    if (along > 4096)
      throw Error("probe spacing " + std::to_string(spacing) + " puts " +
                  std::to_string(std::llround(along)) +
                  " probes along one axis of the scene (at most 4096): raise the spacing");
    grid.counts[std::size_t(a)] = int(along);
    grid.origin[a] = centre[a] - float((along - 1) * spacing / 2);
  }
  return grid;
}

Receivers Receivers::probes_on(const ProbeGrid& grid, std::vector<std::uint8_t> valid) {
  Receivers r;
  r.kind = "probes";
  r.grid = grid;
  r.valid = std::move(valid);
  r.points.positions.reserve(grid.count());
  for (std::size_t p = 0; p < grid.count(); ++p) r.points.positions.push_back(grid.position(p));
  r.points.normals.assign(grid.count(), Eigen::Vector3f::Zero());
  return r;
}

void check_probe_grid(const ProbeGrid& grid, const std::string& source) {
  bool ok = grid.origin.allFinite() && std::isfinite(grid.spacing) && grid.spacing > 0;
  for (int c : grid.counts) ok = ok && c >= 1 && c <= 4096;
  if (!ok)
    throw Error(source + ": the probe grid (spacing " + std::to_string(grid.spacing) + ", counts " +
                std::to_string(grid.counts[0]) + " x " + std::to_string(grid.counts[1]) + " x " +
                std::to_string(grid.counts[2]) + ") is not a grid");
}

Receivers Receivers::texels_of(TexelSamples samples) {
  Receivers r;
  r.kind = "texels";
  r.atlas = std::move(samples.atlas);
  r.points = std::move(samples.points);
  return r;
}

}  // namespace prt
