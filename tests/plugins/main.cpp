// The conformance kit as a Catch2 program: one test case per check of the
// kit (conformance/), run on the plug-in named by --plugin.
//   prt_basis_conformance --plugin NAME      (PRT_KIT_KIND basis)
//   prt_compressor_conformance --plugin NAME (PRT_KIT_KIND compressor)
#define CATCH_CONFIG_RUNNER
// A failure's expression, measured value and tolerance on one line each (the
// default 80 columns wraps them mid-word).
#define CATCH_CONFIG_CONSOLE_WIDTH 300
#include <catch2/catch.hpp>

#include "kit.hpp"

using namespace prt;

namespace {

std::string plugin_name;
PluginKind kind = PluginKind::PRT_KIT_KIND;

// Runs one check of the kit and reports each of its failures to Catch.
class CheckInvoker : public Catch::ITestInvoker {
 public:
  explicit CheckInvoker(const conformance::Check& check) : check_(check) {}
  void invoke() const override {
    PluginRegistry registry{PluginRegistry::default_directories()};
    for (const auto& failure : conformance::run_check(check_, registry, plugin_name))
      FAIL_CHECK(failure);
    SUCCEED();
  }

 private:
  const conformance::Check& check_;
};

}  // namespace

int main(int argc, char** argv) {
  for (const auto& check : conformance::checks(kind))
    Catch::getMutableRegistryHub().registerTest(Catch::makeTestCase(
        new CheckInvoker(check), "", {check.name, check.tags}, CATCH_INTERNAL_LINEINFO));
  Catch::Session session;
  using namespace Catch::clara;
  session.cli(session.cli() | Opt(plugin_name, "name")["--plugin"]("plug-in under test"));
  if (int code = session.applyCommandLine(argc, argv)) return code;
  if (plugin_name.empty()) {
    std::cerr << to_string(kind) << " conformance: give --plugin NAME\n";
    return 2;
  }
  return session.run();
}
