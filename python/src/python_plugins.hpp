// Trampolines: a Python subclass of prt.Basis or prt.Compressor is a C++
// plug-in object. Every call takes the GIL (TBB threads call bases during a
// bake) and checks what Python returned, so a wrong shape is one clear error
// naming the plug-in, never a crash in the pipeline.
#pragma once
#include "bindings.hpp"
#include "prt/basis.hpp"
#include "prt/compressor.hpp"

namespace prt::python {

class PyBasis : public Basis {
 public:
  int size() const override;
  Domain domain() const override;
  bool orthonormal() const override;
  Eigen::MatrixXd evaluate(const Directions& directions) const override;
  Eigen::MatrixXd projection_matrix(const DirectionSet& set) const override;
  Eigen::MatrixXd project(const Eigen::MatrixXd& samples, const DirectionSet& set) const override;
  bool can_rotate() const override;
  Eigen::MatrixXd rotation_matrix(const Eigen::Matrix3d& rotation) const override;
  std::vector<int> coefficient_bands() const override;
  std::optional<DirectionSet> native_directions() const override;
  bool can_fit() const override;
  void fit(const FitData& data) override;
  BasisState save() const override;
  void load(const BasisState& state) override;
};

class PyCompressor : public Compressor {
 public:
  CompressedTransfer encode(const TransferSignal& signal, const Mesh* mesh) const override;
  bool exact() const override;
};

}  // namespace prt::python
