// The conformance kit: checks every plug-in of a kind must pass.
#pragma once
#include <string>

namespace prt::conformance {
extern std::string plugin_name;  // set from --plugin
}
