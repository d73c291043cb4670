#include "plugin_spec.hpp"

#include <sstream>

#include "commands.hpp"
#include "prt/error.hpp"

namespace prt::cli {

PluginSpec parse_plugin_spec(const std::string& text, char separator, const std::string& option) {
  PluginSpec spec{text, "", Params(SourceLocation{option + " \"" + text + "\""})};
  std::stringstream parts(text);
  std::size_t index = 0;
  for (std::string item; std::getline(parts, item, separator);) {
    if (item.empty()) continue;
    if (spec.name.empty())
      spec.name = item;
    else
      parse_parameter(item, index++, spec.params);
  }
  if (spec.name.empty()) throw Error(option + ": an empty plug-in in \"" + text + "\"");
  return spec;
}

}  // namespace prt::cli
