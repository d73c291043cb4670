// Which renderer draws on the GPU: asked of the renderers (a capability),
// never decided by a plug-in's name.
#include "prt/error.hpp"
#include "prt/registry.hpp"
#include "prt/renderer.hpp"

namespace prt {

namespace {

bool draws_on_gpu(PluginRegistry& registry, const std::string& name) {
  try {
    Params defaults;
    return registry.create<Renderer>(name, defaults)->draws_on_gpu();
  } catch (const Error&) {  // a renderer that cannot be made with its defaults is not a choice
    return false;
  }
}

}  // namespace

std::string gpu_renderer(PluginRegistry& registry, const std::string& preferred) {
  if (!preferred.empty() && draws_on_gpu(registry, preferred)) return preferred;
  std::string found;
  for (const std::string& name : registry.names(PluginKind::renderer)) {
    if (draws_on_gpu(registry, name)) return name;
    found += (found.empty() ? "" : ", ") + name;
  }
  throw Error("no renderer plug-in draws on the GPU (found: " + (found.empty() ? "none" : found) +
              "); build the OpenGL renderer (target prt_renderer_opengl) or put one on "
              "PRT_PLUGIN_PATH");
}

}  // namespace prt
