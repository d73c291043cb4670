// A minimal basis plug-in (constant function) used by the registry tests; the
// build defines switch it into each broken variant.
#include <array>
#include <cmath>

#include "prt/basis.hpp"
#include "prt/plugin.hpp"

namespace {

class ConstantBasis final : public prt::Basis {
 public:
  static constexpr const char* plugin_version = "0.0.1";
  static constexpr const char* plugin_description = "test plug-in: the constant function";
  static constexpr auto parameters() {
    return std::array{prt::schema::real("scale", "1", 0, 10, "a parameter for schema tests")};
  }
  explicit ConstantBasis(const prt::Params& params) : scale_(params.get_real("scale")) {
#ifdef PRT_TEST_THROW
    throw prt::Error("this test plug-in always fails to construct");
#endif
  }
  int size() const override {
    return 1;
  }
  bool orthonormal() const override {
    return true;
  }
  Eigen::MatrixXd evaluate(const prt::Directions& d) const override {
    return Eigen::MatrixXd::Constant(d.rows(), 1, scale_ / std::sqrt(4.0 * M_PI));
  }

 private:
  double scale_;
};

constexpr prt::PluginInfoRecord make_info() {
#ifdef PRT_TEST_FOREIGN_ALIGN  // the host's key but for Eigen's alignment
  auto r = prt::make_plugin_info<ConstantBasis>(
      "constant",
      "compiler=" PRT_COMPILER ";cxx11abi=" PRT_STRINGIFY(
          _GLIBCXX_USE_CXX11_ABI) ";stl=" PRT_STL_MODE
                                  ";eigen=" PRT_STRINGIFY(EIGEN_WORLD_VERSION) "." PRT_STRINGIFY(
                                      EIGEN_MAJOR_VERSION) ";align=8");
#elif defined(PRT_TEST_BUILD_KEY)
  auto r = prt::make_plugin_info<ConstantBasis>("constant", PRT_TEST_BUILD_KEY);
#else
  auto r = prt::make_plugin_info<ConstantBasis>("constant", PRT_BUILD_KEY);
#endif
#ifdef PRT_TEST_ABI
  r.abi_version = PRT_TEST_ABI;
#endif
  return r;
}

}  // namespace

extern "C" PRT_PLUGIN_API const prt::PluginInfoRecord prt_plugin_info = make_info();
extern "C" PRT_PLUGIN_API prt::PluginObject* prt_plugin_create(const prt::Params* params,
                                                               char* error,
                                                               std::size_t size) noexcept {
  return prt::detail::create_guarded<ConstantBasis>(params, error, size);
}
#ifndef PRT_TEST_OMIT_DESTROY
extern "C" PRT_PLUGIN_API void prt_plugin_destroy(prt::PluginObject* object) noexcept {
  delete object;
}
#endif
