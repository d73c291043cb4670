#include "prt/point_lights.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "prt/basis.hpp"
#include "prt/error.hpp"
#include "prt/progress.hpp"
#include "prt/transport.hpp"

namespace prt {

namespace {

// An orthonormal frame (columns: two tangents, then `axis`).
Eigen::Matrix3d frame_about(const Eigen::Vector3d& axis) {
  const Eigen::Vector3d helper =
      std::abs(axis.x()) > 0.9 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitX();
  const Eigen::Vector3d t = helper.cross(axis).normalized();
  Eigen::Matrix3d m;
  m << t, axis.cross(t), axis;
  return m;
}

// Cosine of the cap's half angle as seen from `from` (1: a point, or inside).
double cap_cosine(const Eigen::Vector3d& from, const PointLight& light) {
  const double d = (light.position - from).norm();
  if (light.radius <= 0 || d <= light.radius) return 1.0;
  const double s = light.radius / d;
  return std::sqrt(std::max(0.0, 1.0 - s * s));
}

// Uniform direction over the cap {w : w . axis >= cos_max} (frame: columns).
Eigen::Vector3d cap_direction(const Eigen::Matrix3d& frame, double cos_max, double u1, double u2) {
  const double z = 1.0 - u1 * (1.0 - cos_max), r = std::sqrt(std::max(0.0, 1.0 - z * z));
  const double phi = 2 * M_PI * u2;
  return frame * Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z);
}

Eigen::Vector3d toward(const Eigen::Vector3f& from, const Eigen::Vector3d& to) {
  const Eigen::Vector3d d = to - from.cast<double>();
  const double length = d.norm();
  return length > 0 ? Eigen::Vector3d(d / length) : Eigen::Vector3d::UnitY();
}

}  // namespace

PointLightProjector::PointLightProjector(const Basis& basis, int nearest)
    : basis_(&basis), nearest_(nearest) {
  if (nearest < 1) throw Error("point lights: nearest must be at least 1");
  lattice_ = basis.native_directions();
  if (lattice_) {
    rule_ = Rule::nearest;
    nearest_ = std::min<int>(nearest, static_cast<int>(lattice_->size()));
  }
}

PointLightProjector PointLightProjector::brute_force(const Basis& basis, int cap_samples) {
  PointLightProjector p(basis);
  p.rule_ = Rule::brute_force;
  p.cap_samples_ = std::max(1, cap_samples);
  return p;
}

std::string PointLightProjector::describe() const {
  switch (rule_) {
    case Rule::nearest:
      return "the " + std::to_string(nearest_) + " nearest of the basis's " +
             std::to_string(lattice_->size()) + " " + lattice_->kind +
             " directions share each light (Nowrouzezahrai et al. 4.2.1)";
    case Rule::exact:
      return "the basis evaluated at each light's exact direction (no lattice)";
    case Rule::brute_force:
      return "brute-force re-projection of each light's cap, " + std::to_string(cap_samples_) +
             " directions per vertex";
  }
  return "";
}

Eigen::MatrixXd PointLightProjector::light_vectors(const Mesh& mesh,
                                                   const PointLight& light) const {
  const auto v = static_cast<Eigen::Index>(mesh.vertex_count());
  const int n = basis_->size();
  // Directions per vertex: m of them, averaged after evaluating the basis.
  const int m = rule_ == Rule::nearest                           ? nearest_
                : rule_ == Rule::brute_force && light.radius > 0 ? cap_samples_
                                                                 : 1;
  auto directions_of = [&](Eigen::Index p, Directions& out, Eigen::Index row) {
    const Eigen::Vector3d w = toward(mesh.positions[p], light.position);
    if (rule_ == Rule::exact) {
      out.row(row) = w.transpose();
    } else if (rule_ == Rule::nearest) {
      const Directions& lattice = lattice_->directions;
      if (nearest_ == 1 && lattice_->kind == "cubemap") {
        const int r = static_cast<int>(std::lround(std::sqrt(lattice.rows() / 6.0)));
        out.row(row) = lattice.row(cubemap_texel(w, r));
        return;
      }
      std::vector<std::pair<double, Eigen::Index>> by_angle(lattice.rows());
      for (Eigen::Index k = 0; k < lattice.rows(); ++k)
        by_angle[k] = {-lattice.row(k).dot(w.transpose()), k};
      std::partial_sort(by_angle.begin(), by_angle.begin() + nearest_, by_angle.end());
      for (int j = 0; j < nearest_; ++j) out.row(row + j) = lattice.row(by_angle[j].second);
    } else {  // brute force: the cap resampled per vertex (a fixed spiral)
      const Eigen::Matrix3d frame = frame_about(w);
      const double cos_max = cap_cosine(mesh.positions[p].cast<double>(), light);
      for (int k = 0; k < m; ++k)
        out.row(row + k) =
            cap_direction(frame, cos_max, (k + 0.5) / m, std::fmod(0.618034 * k, 1.0)).transpose();
    }
  };
  // Blocks of vertices keep the evaluated basis small (at most 2^16 rows).
  const Eigen::Index block = std::max<Eigen::Index>(1, (Eigen::Index(1) << 16) / m);
  Eigen::MatrixXd out(v, n);
  for (Eigen::Index begin = 0; begin < v; begin += block) {
    const Eigen::Index count = std::min(block, v - begin);
    Directions directions(count * m, 3);
    tbb::parallel_for(Eigen::Index(0), count,
                      [&](Eigen::Index i) { directions_of(begin + i, directions, i * m); });
    const Eigen::MatrixXd values = basis_->evaluate(directions);
    if (values.rows() != count * m || values.cols() != n || !values.allFinite())
      throw Error("point lights: the basis gave values of the wrong shape or with NaN/Inf");
    for (Eigen::Index i = 0; i < count; ++i)
      out.row(begin + i) = values.middleRows(i * m, m).colwise().mean();
  }
  return out;
}

Eigen::MatrixX3f point_light_radiance(const Mesh& mesh, const CompressedTransfer& transfer,
                                      int rows, const PointLightProjector& projector,
                                      const std::vector<PointLight>& lights,
                                      const MatrixXfRow* exit_values) {
  const auto v = static_cast<Eigen::Index>(mesh.vertex_count());
  if (transfer.vertices() != v || rows < 1 || transfer.dimension % rows != 0 ||
      (rows > 1 && (!exit_values || exit_values->rows() != v || exit_values->cols() != rows)))
    throw Error("point lights: transfer, exit values and mesh do not match");
  const Eigen::Index n = transfer.dimension / rows;
  // All lights' vectors first, so that each vertex's transfer is decoded once.
  std::vector<Eigen::MatrixXf> vectors;
  for (const PointLight& light : lights) {
    vectors.push_back(projector.light_vectors(mesh, light).cast<float>());
    if (vectors.back().cols() != n)
      throw Error("point lights: light vectors do not match the transfer");
  }
  Eigen::MatrixX3f out = Eigen::MatrixX3f::Zero(v, 3);
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, v, 256), [&](const auto& range) {
    Eigen::RowVectorXf row(transfer.dimension);
    for (Eigen::Index p = range.begin(); p < range.end(); ++p) {
      transfer.decode_row(p, row);
      const Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>
          m(row.data(), rows, n);
      for (std::size_t i = 0; i < lights.size(); ++i) {
        const auto l = vectors[i].row(p).transpose();
        const float e = rows == 1 ? m.row(0).dot(l.transpose()) : exit_values->row(p) * (m * l);
        out.row(p) += e * lights[i].power().cast<float>().transpose();
      }
    }
  });
  return out;
}

Eigen::MatrixX3f ground_truth_point_lights(const Mesh& mesh, const std::vector<PointLight>& lights,
                                           int samples, std::uint64_t seed,
                                           const Reflectance& reflectance, Progress* progress) {
  RayCaster caster(mesh);
  const auto v = static_cast<Eigen::Index>(mesh.vertex_count());
  Eigen::MatrixX3f out = Eigen::MatrixX3f::Zero(v, 3);
  const int side = std::max(1, static_cast<int>(std::lround(std::sqrt(samples))));
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, v, 32), [&](const auto& range) {
    std::vector<float> origins, directions, far;
    std::vector<std::uint8_t> escaped;
    for (Eigen::Index p = range.begin(); p < range.end(); ++p) {
      std::mt19937_64 rng((seed + 0x632BE59BD9B4E019ull) * 0x9E3779B97F4A7C15ull + p);
      std::uniform_real_distribution<double> jitter(0.0, 1.0);
      const Eigen::Vector3d x = mesh.positions[p].cast<double>();
      const Eigen::Vector3d normal = mesh.normals[p].cast<double>().normalized();
      const Eigen::Vector3d o = x + caster.offset() * normal;
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (const PointLight& light : lights) {
        const double cos_max = cap_cosine(x, light);
        const int m = cos_max < 1 ? side * side : 1;
        const Eigen::Matrix3d frame = frame_about(toward(mesh.positions[p], light.position));
        const double distance = (light.position - x).norm();
        origins.resize(3 * m), directions.resize(3 * m), far.resize(m), escaped.resize(m);
        std::vector<double> cosine(m);
        for (int k = 0; k < m; ++k) {
          const Eigen::Vector3d d =
              m == 1 ? frame.col(2)
                     : cap_direction(frame, cos_max, (k / side + jitter(rng)) / side,
                                     (k % side + jitter(rng)) / side);
          cosine[k] = d.dot(normal);
          for (int c = 0; c < 3; ++c)
            origins[3 * k + c] = float(o[c]), directions[3 * k + c] = float(d[c]);
          // Up to the light's surface (its centre for a point).
          far[k] = float(std::max(0.0, distance - light.radius) * (1 - 1e-4));
        }
        caster.occluded(origins.data(), directions.data(), m, escaped.data(), far.data());
        double lit = 0;
        for (int k = 0; k < m; ++k) {
          if (!escaped[k] || cosine[k] <= 0) continue;
          const Eigen::Vector3d d(directions[3 * k], directions[3 * k + 1], directions[3 * k + 2]);
          lit += cosine[k] / M_PI * (reflectance ? reflectance(std::size_t(p), d) : 1.0);
        }
        sum += (lit / m) * light.power();
      }
      out.row(p) = sum.cast<float>().transpose();
    }
    if (progress) progress->add(double(range.size()));
  });
  return out;
}

}  // namespace prt
