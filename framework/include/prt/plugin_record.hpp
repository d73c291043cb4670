// The plain C-layout info record every plug-in exports. It holds no pointers,
// so the host reads it straight from the library file without loading it.
// The first field is frozen forever: any later layout bumps PRT_ABI_VERSION.
#pragma once
#include <cstdint>

#define PRT_ABI_VERSION 1u

namespace prt {

enum class PluginKind : std::uint32_t { basis = 1, compressor = 2, renderer = 3 };
const char* to_string(PluginKind kind);

enum class ParamType : std::uint32_t { boolean = 1, integer, real, string, reals, path };
const char* to_string(ParamType type);

// One parameter of a schema. Text fields are NUL-terminated.
struct ParamSpecRecord {
  char name[32];
  ParamType type;
  std::uint32_t required;     // 1: must be given
  std::uint32_t list_length;  // for `reals`: exact length, or 0 for any
  double min;                 // for integer/real: inclusive range
  double max;
  char default_value[64];  // textual default ("" = none)
  char choices[160];       // for string: "a|b|c"; empty = any string
  char help[160];
};

constexpr unsigned kMaxParams = 24;

struct PluginInfoRecord {
  std::uint32_t abi_version;  // frozen first field
  std::uint32_t record_size;  // sizeof(PluginInfoRecord) of the plug-in's build
  PluginKind kind;
  char name[48];
  char version[16];
  char build_key[160];
  char description[160];
  std::uint32_t param_count;
  ParamSpecRecord params[kMaxParams];
};

}  // namespace prt

// Names of the exported symbols.
#define PRT_INFO_SYMBOL "prt_plugin_info"
#define PRT_CREATE_SYMBOL "prt_plugin_create"
#define PRT_DESTROY_SYMBOL "prt_plugin_destroy"
