// Discovers plug-ins, reads their info records from the files without loading
// them, and loads a library only when an object of it is created.
#pragma once
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "prt/params.hpp"
#include "prt/plugin.hpp"
#include "prt/plugin_record.hpp"

namespace boost::dll {
class shared_library;
}

namespace prt {

// Makes an object of a plug-in that lives in this process (no library
// file), e.g. a class written in Python; `params` are already validated.
using InProcessFactory = std::function<std::shared_ptr<PluginObject>(Params& params)>;

struct PluginDescriptor {
  std::filesystem::path file;  // in-process plug-ins: where it was defined, in words
  PluginInfoRecord info;
  InProcessFactory factory;  // set for in-process plug-ins only

  PluginKind kind() const { return info.kind; }
  std::string name() const { return info.name; }
  ParamSchema schema() const;
};

// The build key of the host, to compare with each plug-in's.
const char* host_build_key();

// Whether a plug-in recorded as (name, parameters), e.g. in a bake file, is
// the one now named with these parameters. Plug-in identity is the
// registry's business; everything else asks plug-ins for capabilities.
bool same_plugin(const std::string& recorded_name, const std::string& recorded_parameters,
                 const std::string& name, const std::string& parameters);

// A file or folder on the plug-in path that was skipped, and why. `name` is
// the plug-in name it declares, or that its file name suggests (may be empty).
struct PluginProblem {
  std::filesystem::path file;
  PluginKind kind = PluginKind::basis;
  std::string name;
  std::string message;
  bool duplicate = false;  // a valid plug-in whose name another file has too
};

// Registers a plug-in that lives in this process under info.name, in every
// registry, those alive now and those made later. The record is checked as a
// file's would be (a kind, a name, at most kMaxParams parameters); a second
// registration of the same kind and name replaces the first, but a name that
// a library file provides is refused.
void register_in_process(const PluginInfoRecord& info, const std::string& origin,
                         InProcessFactory factory);
// Removes an in-process registration (no effect if there is none).
void unregister_in_process(PluginKind kind, const std::string& name);

class PluginRegistry {
 public:
  // Scans `directories` in order for files named libprt-*.so. A malformed
  // candidate (not a plug-in, wrong ABI or build key, missing symbol), a
  // duplicate name, a missing folder, or a folder or file that others than its
  // owner or root may write is skipped and recorded in problems(). Asking for
  // a duplicated name throws; asking for a name that only a skipped file
  // claims (by its record or its file name) throws that file's problem.
  explicit PluginRegistry(const std::vector<std::filesystem::path>& directories);
  ~PluginRegistry();
  PluginRegistry(const PluginRegistry&) = delete;
  PluginRegistry& operator=(const PluginRegistry&) = delete;

  // The build's plug-in directory followed by every entry of PRT_PLUGIN_PATH.
  static std::vector<std::filesystem::path> default_directories();

  const std::vector<PluginDescriptor>& plugins() const { return plugins_; }
  std::vector<std::string> names(PluginKind kind) const;
  // What was skipped while scanning, one located message each.
  const std::vector<PluginProblem>& problems() const { return problems_; }

  // Throws with the list of available names of that kind when absent.
  const PluginDescriptor& find(PluginKind kind, const std::string& name,
                               const SourceLocation& where = {}) const;

  // Validates `params` against the plug-in's schema, loads the library if
  // needed and creates the object. The returned pointer keeps the library
  // mapped for as long as it lives.
  template <class Interface>
  std::shared_ptr<Interface> create(const std::string& name, Params& params,
                                    const SourceLocation& where = {}) {
    auto object = create_object(Interface::plugin_kind, name, params, where);
    auto* typed = dynamic_cast<Interface*>(object.get());
    if (!typed) throw Error(where, "plug-in \"" + name + "\" does not implement its interface");
    return std::shared_ptr<Interface>(object, typed);
  }

  // Adds or replaces an in-process plug-in in this registry (see
  // register_in_process, which calls it for every live registry).
  void add_in_process(const PluginDescriptor& descriptor);
  void remove_in_process(PluginKind kind, const std::string& name);

  // Number of libraries mapped so far (lazy loading is observable).
  std::size_t loaded_count() const { return modules_.size(); }

 private:
  std::shared_ptr<PluginObject> create_object(PluginKind kind, const std::string& name,
                                              Params& params, const SourceLocation& where);
  void scan(const std::filesystem::path& directory);
  void scan_file(const std::filesystem::path& file);
  std::vector<PluginDescriptor> plugins_;
  std::vector<PluginProblem> problems_;
  std::map<std::filesystem::path, std::shared_ptr<boost::dll::shared_library>> modules_;
};

// The renderer that draws on the GPU (Renderer::draws_on_gpu) for prt-view
// and `prt bench --gpu`: `preferred` (the scene's renderer) when it does, else
// the first registered renderer that does. Throws prt::Error naming the
// renderers found when none does.
std::string gpu_renderer(PluginRegistry& registry, const std::string& preferred);

}  // namespace prt
