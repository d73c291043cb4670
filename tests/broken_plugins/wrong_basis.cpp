// A deliberately wrong basis: SH of order 3 with y_{1,1} scaled by 1.1 (so it
// is not orthonormal, though it claims to be) and a rotation that ignores its
// argument. The conformance kit must fail on it (tests/integration/kit_can_fail.sh).
#include <array>

#include "prt/basis.hpp"
#include "prt/plugin.hpp"
#include "prt/sh.hpp"

namespace {

class WrongBasis final : public prt::Basis {
 public:
  static constexpr const char* plugin_version = "0.0.1";
  static constexpr const char* plugin_description = "test plug-in: a subtly wrong SH basis";
  static constexpr auto parameters() { return std::array<prt::ParamSpecRecord, 0>{}; }
  explicit WrongBasis(const prt::Params&) {}
  int size() const override { return 9; }
  bool orthonormal() const override { return true; }
  Eigen::MatrixXd evaluate(const prt::Directions& d) const override {
    Eigen::MatrixXd y = prt::sh::evaluate(3, d);
    y.col(3) *= 1.1;
    return y;
  }
  bool can_rotate() const override { return true; }
  Eigen::MatrixXd rotation_matrix(const Eigen::Matrix3d&) const override {
    return Eigen::MatrixXd::Identity(9, 9);
  }
};

}  // namespace

PRT_EXPORT_PLUGIN(WrongBasis, "wrong")
