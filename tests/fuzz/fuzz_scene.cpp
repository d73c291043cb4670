// The scene parser (toml++ behind a UTF-8 check, then typed parameters).
#include <cstdint>
#include <string>

#include "prt/error.hpp"
#include "prt/registry.hpp"
#include "prt/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static prt::PluginRegistry registry(prt::PluginRegistry::default_directories());
  try {
    prt::SceneSpec::parse(std::string(reinterpret_cast<const char*>(data), size), "fuzz.toml",
                          registry);
  } catch (const prt::Error&) {
  }
  return 0;
}
