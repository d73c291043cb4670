// Runs the basis conformance checks on the plug-in named by --plugin.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include "conformance.hpp"

std::string prt::conformance::plugin_name;

int main(int argc, char** argv) {
  Catch::Session session;
  using namespace Catch::clara;
  session.cli(session.cli() |
              Opt(prt::conformance::plugin_name, "name")["--plugin"]("plug-in under test"));
  if (int code = session.applyCommandLine(argc, argv)) return code;
  if (prt::conformance::plugin_name.empty()) {
    std::cerr << "basis conformance: give --plugin NAME\n";
    return 2;
  }
  return session.run();
}
