#include "prt/registry.hpp"

#include <dlfcn.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <boost/dll/shared_library.hpp>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <set>

#include "elf_symbols.hpp"

#ifndef PRT_PLUGIN_DIR
#define PRT_PLUGIN_DIR ""
#endif

namespace prt {
namespace fs = std::filesystem;

const char* host_build_key() {
  return PRT_BUILD_KEY;
}

bool same_plugin(const std::string& recorded_name, const std::string& recorded_parameters,
                 const std::string& name, const std::string& parameters) {
  return recorded_name == name && recorded_parameters == parameters;
}

ParamSchema PluginDescriptor::schema() const {
  ParamSchema schema;
  schema.owner = std::string(to_string(kind())) + " \"" + name() + "\"";
  schema.specs.assign(info.params, info.params + std::min(info.param_count, kMaxParams));
  return schema;
}

namespace {

bool is_candidate(const fs::path& file) {
  const std::string name = file.filename().string();
  return name.rfind("libprt-", 0) == 0 && file.extension() == ".so";
}

// Forces every text field to end inside its array, whatever the file held.
void terminate_texts(PluginInfoRecord& info) {
  info.name[sizeof info.name - 1] = info.version[sizeof info.version - 1] = '\0';
  info.build_key[sizeof info.build_key - 1] = info.description[sizeof info.description - 1] = '\0';
  for (auto& p : info.params) {
    p.name[sizeof p.name - 1] = p.default_value[sizeof p.default_value - 1] = '\0';
    p.choices[sizeof p.choices - 1] = p.help[sizeof p.help - 1] = '\0';
  }
}

// "k1=v1;k2=v2" -> the first component that differs, in words ("" if none).
std::string build_key_difference(const std::string& plugin, const std::string& host) {
  auto parse = [](const std::string& key) {
    std::vector<std::pair<std::string, std::string>> parts;
    for (std::size_t start = 0; start <= key.size();) {
      const std::size_t end = std::min(key.find(';', start), key.size());
      const std::string part = key.substr(start, end - start);
      const std::size_t equals = part.find('=');
      parts.emplace_back(part.substr(0, equals),
                         equals == std::string::npos ? "" : part.substr(equals + 1));
      start = end + 1;
    }
    return parts;
  };
  const auto p = parse(plugin), h = parse(host);
  for (const auto& [name, value] : h) {
    const auto it =
        std::find_if(p.begin(), p.end(), [&](const auto& x) { return x.first == name; });
    if (it == p.end()) return "has an old build key without \"" + name + "\" (host: " + value + ")";
    if (it->second != value)
      return "was built with " + name + " = " + it->second + ", but this host has " + name + " = " +
             value;
  }
  return plugin == host ? "" : "has a build key this host does not know";
}

PluginDescriptor read_descriptor(const fs::path& file) {
  const std::string where = file.string();
  const elf::SymbolTable symbols = elf::dynamic_symbols(file);
  const auto bytes = elf::symbol_bytes(file, PRT_INFO_SYMBOL);
  if (!symbols.has(PRT_INFO_SYMBOL) || !bytes)
    throw Error(where + ": not a PRT plug-in (it exports no " PRT_INFO_SYMBOL
                        " record; build it with PRT_EXPORT_PLUGIN)");
  std::uint32_t abi = 0;
  if (bytes->size() >= sizeof abi) std::memcpy(&abi, bytes->data(), sizeof abi);
  if (abi != PRT_ABI_VERSION || bytes->size() != sizeof(PluginInfoRecord))
    throw Error(where + ": plug-in ABI version " + std::to_string(abi) + " (record of " +
                std::to_string(bytes->size()) + " bytes), but this host reads ABI version " +
                std::to_string(PRT_ABI_VERSION) + " (" + std::to_string(sizeof(PluginInfoRecord)) +
                " bytes); rebuild the plug-in against this framework");
  PluginDescriptor d{file, {}};
  std::memcpy(&d.info, bytes->data(), sizeof d.info);
  terminate_texts(d.info);
  if (d.info.kind != PluginKind::basis && d.info.kind != PluginKind::compressor &&
      d.info.kind != PluginKind::renderer)
    throw Error(where + ": plug-in \"" + d.name() + "\" declares an unknown kind " +
                std::to_string(static_cast<unsigned>(d.info.kind)));
  if (const std::string differs = build_key_difference(d.info.build_key, host_build_key());
      !differs.empty())
    throw Error(
        where + ": plug-in \"" + d.name() + "\" " + differs +
        "; rebuild it against this framework with find_package(PRT) (full keys: plug-in \"" +
        d.info.build_key + "\", host \"" + host_build_key() + "\")");
  for (const char* symbol : {PRT_CREATE_SYMBOL, PRT_DESTROY_SYMBOL})
    if (!symbols.has(symbol))
      throw Error(where + ": plug-in \"" + d.name() + "\" lacks the symbol " + symbol +
                  " (was it exported with PRT_EXPORT_PLUGIN?)");
  return d;
}

}  // namespace

namespace {

// `d` skipped because `other` has its kind and name.
PluginProblem duplicate_problem(const PluginDescriptor& d, const PluginDescriptor& other) {
  return {d.file, d.kind(), d.name(),
          d.file.string() + ": duplicate " + to_string(d.kind()) + " plug-in name \"" + d.name() +
              "\", also provided by " + other.file.string(),
          true};
}

// In-process plug-ins and the registries alive, so that a registration
// reaches every registry.
struct InProcessTable {
  std::mutex mutex;
  std::vector<PluginDescriptor> plugins;
  std::set<PluginRegistry*> registries;
};
InProcessTable& in_process_table() {
  static InProcessTable table;
  return table;
}

void check_record(const PluginInfoRecord& info) {
  if (info.kind != PluginKind::basis && info.kind != PluginKind::compressor &&
      info.kind != PluginKind::renderer)
    throw Error("cannot register a plug-in of unknown kind " +
                std::to_string(static_cast<unsigned>(info.kind)));
  if (info.name[0] == '\0') throw Error("cannot register a plug-in without a name");
  if (info.param_count > kMaxParams)
    throw Error(std::string("plug-in \"") + info.name + "\" has " +
                std::to_string(info.param_count) + " parameters; at most " +
                std::to_string(kMaxParams) + " are allowed");
}

}  // namespace

void register_in_process(const PluginInfoRecord& info, const std::string& origin,
                         InProcessFactory factory) {
  check_record(info);
  if (!factory) throw Error(std::string("plug-in \"") + info.name + "\" has no factory");
  PluginDescriptor d{origin, info, std::move(factory)};
  terminate_texts(d.info);
  auto& table = in_process_table();
  std::lock_guard lock(table.mutex);
  for (PluginRegistry* registry : table.registries)  // refuse before changing any
    for (const auto& p : registry->plugins())
      if (!p.factory && p.kind() == d.kind() && p.name() == d.name())
        throw Error(std::string("cannot register ") + to_string(d.kind()) + " \"" + d.name() +
                    "\": the plug-in library " + p.file.string() +
                    " has that name; choose another");
  std::erase_if(table.plugins,
                [&](const auto& p) { return p.kind() == d.kind() && p.name() == d.name(); });
  table.plugins.push_back(d);
  for (PluginRegistry* registry : table.registries) registry->add_in_process(d);
}

void unregister_in_process(PluginKind kind, const std::string& name) {
  auto& table = in_process_table();
  std::lock_guard lock(table.mutex);
  std::erase_if(table.plugins, [&](const auto& p) { return p.kind() == kind && p.name() == name; });
  for (PluginRegistry* registry : table.registries) registry->remove_in_process(kind, name);
}

void PluginRegistry::add_in_process(const PluginDescriptor& descriptor) {
  for (auto& p : plugins_)
    if (p.kind() == descriptor.kind() && p.name() == descriptor.name()) {
      if (!p.factory) {  // a library file has the name: the same answer as two files
        problems_.push_back(duplicate_problem(descriptor, p));
        return;
      }
      p = descriptor;
      return;
    }
  plugins_.push_back(descriptor);
}

void PluginRegistry::remove_in_process(PluginKind kind, const std::string& name) {
  std::erase_if(plugins_,
                [&](const auto& p) { return p.factory && p.kind() == kind && p.name() == name; });
}

PluginRegistry::PluginRegistry(const std::vector<fs::path>& directories) {
  std::vector<fs::path> scanned;
  for (const auto& directory : directories) {
    std::error_code error;
    const bool seen = std::any_of(scanned.begin(), scanned.end(), [&](const fs::path& other) {
      return fs::equivalent(directory, other, error);
    });
    if (seen) continue;  // the same folder twice would make every plug-in a duplicate
    scan(directory);
    scanned.push_back(directory);
  }
  auto& table = in_process_table();
  std::lock_guard lock(table.mutex);
  for (const auto& d : table.plugins) add_in_process(d);
  table.registries.insert(this);
}

PluginRegistry::~PluginRegistry() {
  auto& table = in_process_table();
  std::lock_guard lock(table.mutex);
  table.registries.erase(this);
}

namespace {
// <libdir>/prt/plugins next to this library when it is an installed copy,
// otherwise the plug-in directory of the build tree it was built in.
fs::path own_plugin_directory() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void*>(&host_build_key), &info) && info.dli_fname) {
    const fs::path installed =
        fs::path(info.dli_fname).lexically_normal().parent_path() / "prt" / "plugins";
    std::error_code error;
    if (fs::is_directory(installed, error)) return installed;
  }
  return fs::path(PRT_PLUGIN_DIR);
}
}  // namespace

std::vector<fs::path> PluginRegistry::default_directories() {
  std::vector<fs::path> directories;
  if (const char* extra = std::getenv("PRT_PLUGIN_PATH")) {
    std::string list = extra;
    for (std::size_t start = 0; start <= list.size();) {
      const std::size_t end = std::min(list.find(':', start), list.size());
      if (end > start) directories.emplace_back(list.substr(start, end - start));
      start = end + 1;
    }
  }
  directories.insert(directories.begin(), own_plugin_directory());
  return directories;
}

namespace {

// Code may be loaded only from what no one but its owner (root or this
// user) can change: a folder or file others may write could hold anyone's code.
// A sticky folder (as /tmp) protects its entries, so it may count as safe
// when it is only a parent of the one that holds the code.
enum class Exposure { none, writable, foreign };
Exposure exposure_of(const fs::path& path, bool sticky_is_safe, uid_t& owner) {
  struct stat s {};
  if (stat(path.c_str(), &s) != 0) return Exposure::none;
  owner = s.st_uid;
  if ((s.st_mode & (S_IWGRP | S_IWOTH)) && !(sticky_is_safe && (s.st_mode & S_ISVTX)))
    return Exposure::writable;
  if (s.st_uid != 0 && s.st_uid != geteuid()) return Exposure::foreign;
  return Exposure::none;
}

std::string unsafe_to_load(const fs::path& path, const char* what) {
  uid_t owner = 0;
  switch (exposure_of(path, false, owner)) {
    case Exposure::writable:
      return path.string() + ": skipped: the " + what +
             " is writable by others than its owner (chmod go-w to use it)";
    case Exposure::foreign:
      return path.string() + ": skipped: the " + what + " belongs to another user (uid " +
             std::to_string(owner) + ")";
    case Exposure::none:
      break;
  }
  return "";
}

// A folder is as safe as the folders above it: whoever may write a parent
// may rename the folder away and put their own in its place (or change a
// symlink that leads to it). Every ancestor of the path as written and of
// the path it resolves to is checked as the folder itself is.
std::string unsafe_ancestor(const fs::path& directory) {
  std::error_code error;
  const fs::path written = fs::absolute(directory, error).lexically_normal();
  const fs::path resolved = fs::canonical(directory, error);
  for (const fs::path& path : {written, resolved}) {
    if (path.empty()) continue;
    for (fs::path parent = path.parent_path(); !parent.empty(); parent = parent.parent_path()) {
      uid_t owner = 0;
      const std::string subject =
          directory.string() + ": skipped: the plug-in folder's parent " + parent.string();
      switch (exposure_of(parent, true, owner)) {
        case Exposure::writable:
          return subject + " is writable by others than its owner, who could replace the " +
                 "folder (chmod go-w " + parent.string() + " to use it)";
        case Exposure::foreign:
          return subject + " belongs to another user (uid " + std::to_string(owner) + ")";
        case Exposure::none:
          break;
      }
      if (parent == parent.root_path()) break;
    }
  }
  return "";
}

// "libprt-<kind>-<name>.so": what a file that cannot be read claims to be.
PluginProblem problem_from_file_name(const fs::path& file, std::string message) {
  PluginProblem problem{file, PluginKind::basis, "", std::move(message)};
  std::string stem = file.stem().string().substr(std::strlen("libprt-"));
  for (PluginKind kind : {PluginKind::basis, PluginKind::compressor, PluginKind::renderer}) {
    const std::string prefix = std::string(to_string(kind)) + "-";
    if (stem.rfind(prefix, 0) == 0) {
      problem.kind = kind;
      problem.name = stem.substr(prefix.size());
    }
  }
  return problem;
}

}  // namespace

void PluginRegistry::scan(const fs::path& directory) {
  if (directory.empty()) return;
  std::error_code error;
  if (!fs::is_directory(directory, error)) {
    problems_.push_back({directory, PluginKind::basis, "",
                         directory.string() + ": plug-in directory does not exist"});
    return;
  }
  for (auto why : {unsafe_to_load(directory, "plug-in folder"), unsafe_ancestor(directory)})
    if (!why.empty()) {
      problems_.push_back({directory, PluginKind::basis, "", why});
      return;
    }
  std::vector<fs::path> files;
  for (fs::directory_iterator it(directory, error), end; !error && it != end; it.increment(error))
    if (it->is_regular_file(error) && is_candidate(it->path())) files.push_back(it->path());
  std::sort(files.begin(), files.end());
  for (const auto& file : files) scan_file(file);
}

void PluginRegistry::scan_file(const fs::path& file) {
  if (auto why = unsafe_to_load(file, "plug-in file"); !why.empty()) {
    problems_.push_back(problem_from_file_name(file, why));
    return;
  }
  PluginDescriptor d;
  try {
    d = read_descriptor(file);
  } catch (const Error& e) {
    problems_.push_back(problem_from_file_name(file, e.what()));
    return;
  }
  for (const auto& other : plugins_)
    if (other.kind() == d.kind() && other.name() == d.name()) {
      problems_.push_back(duplicate_problem(d, other));
      return;
    }
  plugins_.push_back(std::move(d));
}

std::vector<std::string> PluginRegistry::names(PluginKind kind) const {
  std::vector<std::string> out;
  for (const auto& p : plugins_)
    if (p.kind() == kind) out.push_back(p.name());
  return out;
}

const PluginDescriptor& PluginRegistry::find(PluginKind kind, const std::string& name,
                                             const SourceLocation& where) const {
  auto problem_claiming = [&](bool duplicate) -> const PluginProblem* {
    for (const auto& problem : problems_)
      if (problem.kind == kind && problem.name == name && problem.duplicate == duplicate)
        return &problem;
    return nullptr;
  };
  if (const auto* ambiguous = problem_claiming(true)) throw Error(where, ambiguous->message);
  for (const auto& p : plugins_)
    if (p.kind() == kind && p.name() == name) return p;
  // Only a skipped file claims this name: its problem is the answer.
  if (const auto* skipped = problem_claiming(false)) throw Error(where, skipped->message);
  const auto available = names(kind);
  std::string list;
  for (const auto& n : available) list += (list.empty() ? "" : ", ") + n;
  std::string message = std::string("no ") + to_string(kind) + " plug-in named \"" + name +
                        "\"; available: " + (list.empty() ? "(none found)" : list);
  const std::string suggestion = closest_match(name, available);
  if (!suggestion.empty())
    message += " (did you mean \"" + suggestion + "\"?)";
  else  // a Python class registered in another process is not on any path
    message +=
        "; a plug-in written in Python exists only in the Python process that registers it "
        "(docs/python.md), a library file only on the plug-in path (PRT_PLUGIN_PATH)";
  throw Error(where, message);
}

std::shared_ptr<PluginObject> PluginRegistry::create_object(PluginKind kind,
                                                            const std::string& name, Params& params,
                                                            const SourceLocation& where) {
  const PluginDescriptor& d = find(kind, name, where);
  params.validate(d.schema());
  if (d.factory) {  // in-process: no library to load
    // Copies: the factory (Python code) may register plug-ins, which changes plugins_.
    InProcessFactory factory = d.factory;
    const std::string origin = d.file.string();
    std::shared_ptr<PluginObject> object;
    try {
      object = factory(params);
    } catch (const Error&) {
      throw;
    } catch (const std::exception& e) {
      throw Error(where, std::string(to_string(kind)) + " \"" + name + "\" (" + origin +
                             ") failed to construct: " + e.what());
    }
    if (!object)
      throw Error(where, std::string(to_string(kind)) + " \"" + name + "\" (" + origin +
                             ") made no object");
    return object;
  }

  auto& module = modules_[d.file];
  if (!module) {
    try {
      module = std::make_shared<boost::dll::shared_library>(
          boost::dll::fs::path(d.file.string()),
          boost::dll::load_mode::rtld_now | boost::dll::load_mode::rtld_local);
    } catch (const std::exception& e) {
      modules_.erase(d.file);
      throw Error(where, d.file.string() + ": cannot load plug-in \"" + name + "\": " + e.what());
    }
  }
  auto& create = module->get<PrtCreateFunction>(PRT_CREATE_SYMBOL);
  PrtDestroyFunction* destroy = &module->get<PrtDestroyFunction>(PRT_DESTROY_SYMBOL);

  char message[1024] = "";
  PluginObject* raw = create(&params, message, sizeof message);
  if (!raw)
    throw Error(where, std::string(to_string(kind)) + " \"" + name + "\" (" + d.file.string() +
                           ") failed to construct: " + message);
  // The deleter holds the module, so the library stays mapped while the object lives.
  std::shared_ptr<boost::dll::shared_library> keep = module;
  return std::shared_ptr<PluginObject>(raw, [keep, destroy](PluginObject* p) { destroy(p); });
}

}  // namespace prt
