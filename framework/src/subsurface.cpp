#include "prt/subsurface.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>

#include "prt/error.hpp"

namespace prt {

const SubsurfacePreset* subsurface_preset(const std::string& name) {
  static const SubsurfacePreset presets[] = {
      {"apple", {2.29, 2.39, 1.97}, {0.0030, 0.0034, 0.046}},
      {"chicken1", {0.15, 0.21, 0.38}, {0.015, 0.077, 0.19}},
      {"chicken2", {0.19, 0.25, 0.32}, {0.018, 0.088, 0.20}},
      {"cream", {7.38, 5.47, 3.15}, {0.0002, 0.0028, 0.0163}},
      {"ketchup", {0.18, 0.07, 0.03}, {0.061, 0.97, 1.45}},
      {"marble", {2.19, 2.62, 3.00}, {0.0021, 0.0041, 0.0071}},
      {"potato", {0.68, 0.70, 0.55}, {0.0024, 0.0090, 0.12}},
      {"skimmilk", {0.70, 1.22, 1.90}, {0.0014, 0.0025, 0.0142}},
      {"skin1", {0.74, 0.88, 1.01}, {0.032, 0.17, 0.48}},
      {"skin2", {1.09, 1.59, 1.79}, {0.013, 0.070, 0.145}},
      {"wholemilk", {2.55, 3.21, 3.77}, {0.0011, 0.0024, 0.014}}};
  for (const auto& preset : presets)
    if (name == preset.name) return &preset;
  return nullptr;
}

double diffuse_fresnel_reflectance(double eta) {
  return -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
}

namespace {

struct Dipole {
  double sigma_tr, alpha, z_r, z_v;
  explicit Dipole(const SubsurfaceMaterial& m) {
    const double sigma_t = m.sigma_a + m.sigma_s;
    alpha = m.sigma_s / sigma_t;
    sigma_tr = std::sqrt(3.0 * m.sigma_a * sigma_t);
    const double f_dr = diffuse_fresnel_reflectance(m.eta);
    const double a = (1.0 + f_dr) / (1.0 - f_dr);
    z_r = 1.0 / sigma_t;
    z_v = z_r * (1.0 + 4.0 / 3.0 * a);
  }
  double operator()(double r) const {
    const double d_r = std::sqrt(r * r + z_r * z_r), d_v = std::sqrt(r * r + z_v * z_v);
    return alpha / (4 * M_PI) *
           (z_r * (sigma_tr * d_r + 1) * std::exp(-sigma_tr * d_r) / (d_r * d_r * d_r) +
            z_v * (sigma_tr * d_v + 1) * std::exp(-sigma_tr * d_v) / (d_v * d_v * d_v));
  }
};

void check(const SubsurfaceMaterial& m) {
  if (!(m.sigma_a > 0) || !(m.sigma_s > 0) || !(m.eta > 0) || !(m.mm_per_unit > 0) ||
      !(m.error >= 0))
    throw Error("subsurface: sigma_a, sigma_s, eta and mm_per_unit must be positive");
}

// A binary hierarchy over the vertices (median split on the longest axis);
// each node aggregates area, area-weighted centroid and sum of A_q t_q.
struct Node {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double radius = 0, area = 0;
  int begin = 0, end = 0, left = -1, right = -1;
};

constexpr int kLeaf = 8;

}  // namespace

double dipole_profile(const SubsurfaceMaterial& m, double r_mm) {
  check(m);
  return Dipole(m)(r_mm);
}

double dipole_total_reflectance(const SubsurfaceMaterial& m) {
  check(m);
  const double f_dr = diffuse_fresnel_reflectance(m.eta);
  const double a = (1.0 + f_dr) / (1.0 - f_dr);
  const double alpha = m.sigma_s / (m.sigma_a + m.sigma_s), root = std::sqrt(3.0 * (1.0 - alpha));
  return 0.5 * alpha * (1.0 + std::exp(-4.0 / 3.0 * a * root)) * std::exp(-root);
}

std::vector<double> vertex_areas(const Mesh& mesh) {
  std::vector<double> area(mesh.vertex_count(), 0.0);
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>();
    const double third = 0.5 / 3.0 *
                         (mesh.positions[t[1]].cast<double>() - a)
                             .cross(mesh.positions[t[2]].cast<double>() - a)
                             .norm();
    for (auto v : t) area[v] += third;
  }
  return area;
}

// The hierarchy, built once: positions and areas in mm, and per node the sum
// of A_q t_q of its vertices.
struct SubsurfaceScattering::Hierarchy {
  SubsurfaceMaterial material;
  Dipole profile;
  double f_dt;
  std::vector<double> area;
  std::vector<Eigen::Vector3d> position;
  std::vector<int> order;
  std::vector<Node> nodes;
  Eigen::MatrixXd aggregate;
  const MatrixXfRow& transfer;
  Hierarchy(const MatrixXfRow& transfer, const SubsurfaceMaterial& m)
      : material(m),
        profile(m),
        f_dt(1.0 - diffuse_fresnel_reflectance(m.eta)),
        transfer(transfer) {}
};

SubsurfaceScattering::SubsurfaceScattering(const Mesh& mesh, const MatrixXfRow& transfer,
                                           const SubsurfaceMaterial& m) {
  check(m);
  const auto v_count = static_cast<int>(mesh.vertex_count());
  if (transfer.rows() != v_count) throw Error("subsurface: transfer rows do not match the mesh");
  auto h = std::make_unique<Hierarchy>(transfer, m);
  const double scale = m.mm_per_unit;
  std::vector<double>& area = h->area;
  area = vertex_areas(mesh);
  for (double& a : area) a *= scale * scale;  // mm^2
  std::vector<Eigen::Vector3d>& position = h->position;
  position.resize(std::size_t(v_count));
  for (int v = 0; v < v_count; ++v) position[v] = mesh.positions[v].cast<double>() * scale;

  // Build the hierarchy over a permutation of the vertices.
  std::vector<int>& order = h->order;
  order.resize(std::size_t(v_count));
  std::iota(order.begin(), order.end(), 0);
  std::vector<Node>& nodes = h->nodes;
  nodes.reserve(2 * v_count / kLeaf + 2);
  std::function<int(int, int)> build = [&](int begin, int end) {
    const int id = static_cast<int>(nodes.size());
    nodes.push_back({});
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double area_sum = 0;
    for (int i = begin; i < end; ++i) {
      lo = lo.cwiseMin(position[order[i]]);
      hi = hi.cwiseMax(position[order[i]]);
      sum += area[order[i]] * position[order[i]];
      area_sum += area[order[i]];
    }
    Node node;
    node.begin = begin, node.end = end, node.area = area_sum;
    node.centroid = area_sum > 0 ? Eigen::Vector3d(sum / area_sum) : 0.5 * (lo + hi);
    for (int i = begin; i < end; ++i)
      node.radius = std::max(node.radius, (position[order[i]] - node.centroid).norm());
    if (end - begin > kLeaf) {
      int axis;
      (hi - lo).maxCoeff(&axis);
      const int mid = (begin + end) / 2;
      std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                       [&](int a, int b) { return position[a][axis] < position[b][axis]; });
      node.left = build(begin, mid);
      node.right = build(mid, end);
    }
    nodes[id] = node;
    return id;
  };
  build(0, v_count);
  // Aggregated A_q t_q per node, children before parents (they have larger ids).
  const Eigen::Index n = transfer.cols();
  Eigen::MatrixXd& aggregate = h->aggregate;
  aggregate = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(nodes.size()), n);
  for (int id = static_cast<int>(nodes.size()) - 1; id >= 0; --id) {
    const Node& node = nodes[id];
    if (node.left < 0)
      for (int i = node.begin; i < node.end; ++i)
        aggregate.row(id) += area[order[i]] * transfer.row(order[i]).cast<double>();
    else
      aggregate.row(id) = aggregate.row(node.left) + aggregate.row(node.right);
  }
  hierarchy_ = std::move(h);
}

SubsurfaceScattering::~SubsurfaceScattering() = default;

MatrixXfRow SubsurfaceScattering::rows(std::size_t first, std::size_t last) const {
  const Hierarchy& h = *hierarchy_;
  if (first > last || last > h.position.size())
    throw Error("subsurface: rows " + std::to_string(first) + " to " + std::to_string(last) +
                " of " + std::to_string(h.position.size()) + " vertices");
  const Eigen::Index n = h.transfer.cols();
  MatrixXfRow out(Eigen::Index(last - first), n);
  tbb::parallel_for(int(first), int(last), [&](int p) {
    Eigen::RowVectorXd sum = Eigen::RowVectorXd::Zero(n);
    std::vector<int> stack{0};
    while (!stack.empty()) {
      const Node& node = h.nodes[stack.back()];
      const int id = stack.back();
      stack.pop_back();
      const double distance = (h.position[p] - node.centroid).norm();
      if (node.left >= 0 && node.radius > h.material.error * distance) {
        stack.push_back(node.left);
        stack.push_back(node.right);
      } else if (node.left >= 0) {
        sum += h.profile(distance) * h.aggregate.row(id);
      } else {
        for (int i = node.begin; i < node.end; ++i) {
          const int q = h.order[i];
          sum += h.profile((h.position[p] - h.position[q]).norm()) * h.area[q] *
                 h.transfer.row(q).cast<double>();
        }
      }
    }
    out.row(Eigen::Index(p - int(first))) = (h.f_dt * h.f_dt * sum).cast<float>();
  });
  return out;
}

MatrixXfRow subsurface_transfer(const Mesh& mesh, const MatrixXfRow& transfer,
                                const SubsurfaceMaterial& m) {
  return SubsurfaceScattering(mesh, transfer, m).rows(0, mesh.vertex_count());
}

Eigen::MatrixX3f subsurface_direct(const Mesh& mesh, const Eigen::MatrixX3f& irradiance,
                                   const SubsurfaceMaterial& m) {
  return subsurface_direct_columns(mesh, Eigen::MatrixXf(irradiance), m);
}

Eigen::MatrixXf subsurface_direct_columns(const Mesh& mesh, const Eigen::MatrixXf& irradiance,
                                          const SubsurfaceMaterial& m) {
  check(m);
  const auto v = static_cast<Eigen::Index>(mesh.vertex_count());
  if (irradiance.rows() != v) throw Error("subsurface: irradiance rows do not match the mesh");
  const Dipole profile(m);
  const double scale = m.mm_per_unit, f_dt = 1.0 - diffuse_fresnel_reflectance(m.eta);
  const std::vector<double> area = vertex_areas(mesh);
  Eigen::Array3Xd position(3, v);
  Eigen::MatrixXd weighted(v, irradiance.cols());  // A_q (mm^2) E_q / pi
  for (Eigen::Index q = 0; q < v; ++q) {
    position.col(q) = mesh.positions[q].cast<double>() * scale;
    weighted.row(q) = area[q] * scale * scale * irradiance.row(q).cast<double>();
  }
  const double z_r = profile.z_r, z_v = profile.z_v, sigma_tr = profile.sigma_tr;
  Eigen::MatrixXf out(v, irradiance.cols());
  // Every pair, in vectorised rows: R_d(|x_p - x_q|) for all q at once.
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, v, 64), [&](const auto& range) {
    Eigen::ArrayXd r2(v), d_r(v), d_v(v), rd(v);
    for (Eigen::Index p = range.begin(); p < range.end(); ++p) {
      r2 = (position.colwise() - position.col(p)).square().colwise().sum().transpose();
      d_r = (r2 + z_r * z_r).sqrt();
      d_v = (r2 + z_v * z_v).sqrt();
      rd = profile.alpha / (4 * M_PI) *
           (z_r * (sigma_tr * d_r + 1) * (-sigma_tr * d_r).exp() / d_r.cube() +
            z_v * (sigma_tr * d_v + 1) * (-sigma_tr * d_v).exp() / d_v.cube());
      out.row(p) = (f_dt * f_dt * (rd.matrix().transpose() * weighted)).cast<float>();
    }
  });
  return out;
}

}  // namespace prt
