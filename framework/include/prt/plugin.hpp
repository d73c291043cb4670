// What a plug-in includes to export itself: PRT_EXPORT_PLUGIN(Class, "name").
//
// The exported info record is constant data (no pointers, no constructors), so
// the host reads kind, name, version, build key and parameter schema from the
// file before it loads any plug-in code. `create` and `destroy` are plain C
// functions; exceptions from a constructor are caught here and turned into a
// message, so none crosses the library boundary.
#pragma once
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstring>
#include <exception>
#include <string>
#include <utility>
#include <vector>

#include "prt/params.hpp"
#include "prt/plugin_record.hpp"

#define PRT_STRINGIFY_(x) #x
#define PRT_STRINGIFY(x) PRT_STRINGIFY_(x)
#if defined(__clang__)
#define PRT_COMPILER "clang-" PRT_STRINGIFY(__clang_major__)
#elif defined(__GNUC__)
#define PRT_COMPILER "gcc-" PRT_STRINGIFY(__GNUC__)
#else
#define PRT_COMPILER "unknown"
#endif
#if defined(_GLIBCXX_DEBUG)
#define PRT_STL_MODE "debug"
#else
#define PRT_STL_MODE "normal"
#endif
// Only what must agree between host and plug-in for C++ objects and Eigen
// matrices to cross the boundary: the compiler family and major version, the
// libstdc++ string ABI and debug containers, Eigen's version and its maximum
// alignment. NDEBUG and optimisation do not change a layout, so Debug,
// RelWithDebInfo and Release plug-ins load into any host. PRT::prt passes
// consumers EIGEN_MAX_ALIGN_BYTES (the framework's value), so a plug-in built
// without -march=native still matches a host built with it.
#define PRT_BUILD_KEY                                                                         \
  "compiler=" PRT_COMPILER ";cxx11abi=" PRT_STRINGIFY(                                        \
      _GLIBCXX_USE_CXX11_ABI) ";stl=" PRT_STL_MODE                                            \
                              ";eigen=" PRT_STRINGIFY(EIGEN_WORLD_VERSION) "." PRT_STRINGIFY( \
                                  EIGEN_MAJOR_VERSION) ";align=" PRT_STRINGIFY(EIGEN_MAX_ALIGN_BYTES)

#define PRT_PLUGIN_API __attribute__((visibility("default")))

namespace prt {

// Base of every object a plug-in creates; destroyed only by its own module.
class PluginObject {
 public:
  virtual ~PluginObject() = default;
};

namespace schema {

constexpr void copy_text(char* dst, std::size_t capacity, const char* src) {
  std::size_t i = 0;
  for (; src && src[i] != '\0' && i + 1 < capacity; ++i) dst[i] = src[i];
  dst[i] = '\0';
}

constexpr ParamSpecRecord make(const char* name, ParamType type, const char* default_value,
                               double min, double max, const char* choices, const char* help,
                               std::uint32_t list_length = 0, bool required = false) {
  ParamSpecRecord r{};
  copy_text(r.name, sizeof r.name, name);
  r.type = type;
  r.required = required ? 1u : 0u;
  r.list_length = list_length;
  r.min = min;
  r.max = max;
  copy_text(r.default_value, sizeof r.default_value, default_value);
  copy_text(r.choices, sizeof r.choices, choices);
  copy_text(r.help, sizeof r.help, help);
  return r;
}

constexpr double kHuge = 1e300;

constexpr ParamSpecRecord integer(const char* name, const char* default_value, double min,
                                  double max, const char* help) {
  return make(name, ParamType::integer, default_value, min, max, "", help);
}
constexpr ParamSpecRecord real(const char* name, const char* default_value, double min, double max,
                               const char* help) {
  return make(name, ParamType::real, default_value, min, max, "", help);
}
constexpr ParamSpecRecord boolean(const char* name, const char* default_value, const char* help) {
  return make(name, ParamType::boolean, default_value, 0, 1, "", help);
}
constexpr ParamSpecRecord choice(const char* name, const char* default_value, const char* choices,
                                 const char* help) {
  return make(name, ParamType::string, default_value, 0, 0, choices, help);
}
constexpr ParamSpecRecord text(const char* name, const char* default_value, const char* help) {
  return make(name, ParamType::string, default_value, 0, 0, "", help);
}
// A file that must exist; relative paths are resolved against the scene file.
constexpr ParamSpecRecord path(const char* name, bool required, const char* help) {
  return make(name, ParamType::path, "", 0, 0, "", help, 0, required);
}
// A list of reals of a fixed length (0 = any); a single number is broadcast.
constexpr ParamSpecRecord reals(const char* name, const char* default_value, std::uint32_t length,
                                double min, double max, const char* help) {
  return make(name, ParamType::reals, default_value, min, max, "", help, length);
}

}  // namespace schema

// A parameter declared once: its schema record (what parameters() lists and
// the registry reads from the ELF file) and its typed reader, so a plug-in
// names each key in one place:
//   static constexpr auto kOrder = param::integer("order", "6", 1, 200, "bands");
//   static constexpr auto parameters() { return param::records(kOrder); }
//   explicit MyBasis(const Params& params) : order_(int(kOrder(params))) {}
// The schema:: records above remain for plug-ins written before (their
// readers name the key again: params.get_int("order")).
template <class T>
struct Param {
  ParamSpecRecord record;
  constexpr operator ParamSpecRecord() const { return record; }
  const char* name() const { return record.name; }
  // The validated value: given in the scene, or the schema's default.
  T operator()(const Params& params) const;
  // Whether the scene gave it (not the default).
  bool given(const Params& params) const { return params.has(record.name); }
};
template <>
inline bool Param<bool>::operator()(const Params& params) const {
  return params.get_bool(record.name);
}
template <>
inline std::int64_t Param<std::int64_t>::operator()(const Params& params) const {
  return params.get_int(record.name);
}
template <>
inline double Param<double>::operator()(const Params& params) const {
  return params.get_real(record.name);
}
template <>
inline std::string Param<std::string>::operator()(const Params& params) const {
  return params.get_string(record.name);
}
template <>
inline std::vector<double> Param<std::vector<double>>::operator()(const Params& params) const {
  return params.get_reals(record.name);
}

// A choice read as an enumeration: each value is named once, and the same
// names make the schema record's "a|b|c" list.
//   static constexpr auto kMethod = param::choice<Method>(
//       "method", "fast", {{"fast", Method::fast}, {"exact", Method::exact}}, "how");
//   const Method method = kMethod(params);
template <class Enum, std::size_t N>
struct Choice {
  ParamSpecRecord record;
  std::array<std::pair<const char*, Enum>, N> values;
  constexpr operator ParamSpecRecord() const { return record; }
  const char* name() const { return record.name; }
  Enum operator()(const Params& params) const {
    const std::string value = params.get_string(record.name);
    for (const auto& [text, e] : values)
      if (value == text) return e;
    params.fail(record.name, "unknown value \"" + value + "\"");  // the schema lets none through
  }
  bool given(const Params& params) const { return params.has(record.name); }
};

namespace param {

template <class Enum, std::size_t N>
constexpr Choice<Enum, N> choice(const char* name, const char* default_value,
                                 const std::pair<const char*, Enum> (&values)[N],
                                 const char* help) {
  char joined[sizeof(ParamSpecRecord::choices)]{};
  std::size_t at = 0;
  for (std::size_t i = 0; i < N; ++i) {
    if (i > 0 && at + 1 < sizeof joined) joined[at++] = '|';
    for (const char* c = values[i].first; *c && at + 1 < sizeof joined; ++c) joined[at++] = *c;
  }
  Choice<Enum, N> result{schema::choice(name, default_value, joined, help), {}};
  for (std::size_t i = 0; i < N; ++i) result.values[i] = values[i];
  return result;
}

constexpr Param<std::int64_t> integer(const char* name, const char* default_value, double min,
                                      double max, const char* help) {
  return {schema::integer(name, default_value, min, max, help)};
}
constexpr Param<double> real(const char* name, const char* default_value, double min, double max,
                             const char* help) {
  return {schema::real(name, default_value, min, max, help)};
}
constexpr Param<bool> boolean(const char* name, const char* default_value, const char* help) {
  return {schema::boolean(name, default_value, help)};
}
constexpr Param<std::string> choice(const char* name, const char* default_value,
                                    const char* choices, const char* help) {
  return {schema::choice(name, default_value, choices, help)};
}
constexpr Param<std::string> text(const char* name, const char* default_value, const char* help) {
  return {schema::text(name, default_value, help)};
}
constexpr Param<std::string> path(const char* name, bool required, const char* help) {
  return {schema::path(name, required, help)};
}
constexpr Param<std::vector<double>> reals(const char* name, const char* default_value,
                                           std::uint32_t length, double min, double max,
                                           const char* help) {
  return {schema::reals(name, default_value, length, min, max, help)};
}

// The schema of a plug-in's parameters, in order (what parameters() returns).
template <class... Keys>
constexpr std::array<ParamSpecRecord, sizeof...(Keys)> records(const Keys&... keys) {
  return {ParamSpecRecord(keys)...};
}

}  // namespace param

template <class Plugin>
constexpr PluginInfoRecord make_plugin_info(const char* name, const char* build_key) {
  constexpr auto params = Plugin::parameters();
  static_assert(params.size() <= kMaxParams, "too many parameters for one plug-in");
  PluginInfoRecord r{};
  r.abi_version = PRT_ABI_VERSION;
  r.record_size = sizeof(PluginInfoRecord);
  r.kind = Plugin::plugin_kind;
  schema::copy_text(r.name, sizeof r.name, name);
  schema::copy_text(r.version, sizeof r.version, Plugin::plugin_version);
  schema::copy_text(r.build_key, sizeof r.build_key, build_key);
  schema::copy_text(r.description, sizeof r.description, Plugin::plugin_description);
  r.param_count = static_cast<std::uint32_t>(params.size());
  for (std::size_t i = 0; i < params.size(); ++i) r.params[i] = params[i];
  return r;
}

namespace detail {

inline void write_error(char* buffer, std::size_t size, const char* message) {
  if (!buffer || size == 0) return;
  std::strncpy(buffer, message, size - 1);
  buffer[size - 1] = '\0';
}

template <class Plugin>
PluginObject* create_guarded(const Params* params, char* error, std::size_t error_size) noexcept {
  try {
    return new Plugin(*params);
  } catch (const std::exception& e) {
    write_error(error, error_size, e.what());
  } catch (...) {
    write_error(error, error_size, "unknown exception");
  }
  return nullptr;
}

}  // namespace detail
}  // namespace prt

using PrtCreateFunction = prt::PluginObject*(const prt::Params*, char*, std::size_t) noexcept;
using PrtDestroyFunction = void(prt::PluginObject*) noexcept;

#define PRT_EXPORT_PLUGIN(Class, name)                                                    \
  extern "C" PRT_PLUGIN_API const prt::PluginInfoRecord prt_plugin_info =                 \
      prt::make_plugin_info<Class>(name, PRT_BUILD_KEY);                                  \
  extern "C" PRT_PLUGIN_API prt::PluginObject* prt_plugin_create(                         \
      const prt::Params* params, char* error, std::size_t error_size) noexcept {          \
    return prt::detail::create_guarded<Class>(params, error, error_size);                 \
  }                                                                                       \
  extern "C" PRT_PLUGIN_API void prt_plugin_destroy(prt::PluginObject* object) noexcept { \
    delete object;                                                                        \
  }
