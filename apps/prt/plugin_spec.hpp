// A plug-in named on the command line with its parameters, as
// `compare-bases --bases "haar:k=96"` and `compress --sweep "cpca clusters=64"`
// write them.
#pragma once
#include <string>

#include "prt/params.hpp"

namespace prt::cli {

struct PluginSpec {
  std::string text, name;  // as given, and the plug-in's name
  Params params;           // typed as TOML types them, located at `option "text"`
};

// "NAME<separator>k=v<separator>k=v...": ':' for --bases, ' ' for --sweep
// (runs of spaces count as one).
PluginSpec parse_plugin_spec(const std::string& text, char separator, const std::string& option);

}  // namespace prt::cli
