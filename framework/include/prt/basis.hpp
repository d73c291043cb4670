// The basis interface: a set of functions over the sphere (or hemisphere).
#pragma once
#include <Eigen/Core>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "prt/direction_set.hpp"
#include "prt/plugin.hpp"
#include "prt/row_parts.hpp"

namespace prt {

struct Mesh;
class VisibilityBits;
class PartKeeper;  // prt/part_keeper.hpp

// What a data-driven basis is fitted to: the mesh, the direction set and the
// traced visibility (1 bit per vertex and direction). In a distributed bake
// each part of the run holds the bits of its shard only: `visibility` has a
// row per vertex parts->shard() of the mesh, and sums over vertices go
// through the parts (prt/row_parts.hpp), so that every part fits the same
// basis, bit for bit the one a single process fits. The defaults are one
// process holding every vertex.
struct FitData {
  const Mesh* mesh = nullptr;
  const DirectionSet* directions = nullptr;
  const VisibilityBits* visibility = nullptr;
  std::shared_ptr<const RowParts> parts;  // null: one process, every vertex
  // Where a long fit may keep its state (the first part writes, every part
  // reads), so that a killed bake resumes inside it; null: nowhere.
  const PartKeeper* checkpoint = nullptr;

  // The parts, or a single part holding the whole mesh by default.
  std::shared_ptr<const RowParts> row_parts() const;
  Shard rows() const { return row_parts()->shard(); }
};

enum class Domain { sphere, hemisphere };

// Fitted state of a data-driven basis, stored in the bake file.
struct BasisState {
  std::map<std::string, Eigen::MatrixXd> matrices;
};

class Basis : public PluginObject {
 public:
  static constexpr PluginKind plugin_kind = PluginKind::basis;

  // Number of coefficients.
  virtual int size() const = 0;
  virtual Domain domain() const { return Domain::sphere; }
  // True if the basis is orthonormal over its domain. The conformance kit
  // checks the claim (its Gram matrix on the kit's rule is the identity);
  // a basis that is not orthonormal says false and the framework uses its
  // metric (prt/basis_metric.hpp), so relighting is right either way.
  virtual bool orthonormal() const = 0;

  // Basis values at the directions: s x size().
  virtual Eigen::MatrixXd evaluate(const Directions& directions) const = 0;

  // The s x size() matrix P with coefficients = samples * P for functions
  // sampled on `set` (one row per function): least-squares coefficients,
  // f ~ sum_i c_i B_i. Default: diag(weights) * evaluate * G^-1, with the
  // basis's Gram matrix G (prt/basis_metric.hpp; G = I, so plain quadrature,
  // for an orthonormal basis). A basis with its own least squares overrides it.
  virtual Eigen::MatrixXd projection_matrix(const DirectionSet& set) const;

  // Projects a batch of functions sampled on `set` (m x s) to m x size().
  // Default: samples * projection_matrix(set). Bases with a fast transform
  // (e.g. Haar on its cube map) override it and say so below, so the bake
  // never forms the s x size() matrix.
  virtual Eigen::MatrixXd project(const Eigen::MatrixXd& samples, const DirectionSet& set) const;
  virtual bool has_fast_projection(const DirectionSet&) const { return false; }

  // Capability: projection of an equirectangular RGB image (width x height
  // texels, rgb interleaved, each sampled at its centre with its exact solid
  // angle, as DirectionSet::equirect) without evaluating the basis per texel,
  // e.g. SH by a separable transform. Returns size() x 3, or nothing when the
  // basis has no such transform (the caller projects through the directions).
  virtual std::optional<Eigen::MatrixX3d> project_equirect(int /*width*/, int /*height*/,
                                                           const float* /*rgb*/) const {
    return std::nullopt;
  }

  // Capability: rotation of coefficient vectors. rotation_matrix(R) returns the
  // size() x size() matrix that maps coefficients of f to those of f(R^T .).
  virtual bool can_rotate() const { return false; }
  virtual Eigen::MatrixXd rotation_matrix(const Eigen::Matrix3d& rotation) const;

  // Capability: the frequency band of each coefficient (SH: l), so that a
  // light can be windowed band by band ([lighting] window) and glossy transfer
  // can band-limit the BRDF to the light's bandwidth. Empty: no bands.
  virtual std::vector<int> coefficient_bands() const { return {}; }

  // A direction set on which the basis's own projection is exact (e.g. the
  // upper-hemisphere rule of a hemispherical basis, a basis's lattice), used by
  // the conformance tests; none for bases happy with any sphere rule.
  virtual std::optional<DirectionSet> native_directions() const { return std::nullopt; }

  // Capability: non-linear approximation keeping this many largest
  // coefficients per vertex, stored sparsely (0: none).
  virtual int approximation_terms() const { return 0; }

  // Throws (one clear message) if the basis cannot serve a bake over this
  // direction set, e.g. a fit that needs a cube-map lattice. The bake plan
  // asks before any ray is traced. Default: any set.
  virtual void check_directions(const DirectionSet&) const {}

  // Capability: fitting to data (data-driven bases such as eigentransport).
  virtual bool can_fit() const { return false; }
  virtual void fit(const FitData&) {}
  // Capability: fit() works from a shard of the visibility per part of the
  // run (FitData::parts), so prt-mpi can bake with this basis. A basis without it
  // is refused by prt-mpi before any ray.
  virtual bool can_fit_distributed() const { return false; }

  // Fitted state, saved to and restored from the bake file.
  virtual BasisState save() const { return {}; }
  virtual void load(const BasisState&) {}
};

}  // namespace prt
