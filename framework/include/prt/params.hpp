// Typed plug-in and scene-section parameters, validated against a schema
// before any work starts.
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <variant>
#include <vector>

#include "prt/error.hpp"
#include "prt/plugin_record.hpp"

namespace prt {

// A parameter value as written in the scene: bool, integer, real, string or a
// list of reals (colours, vectors).
using ParamValue = std::variant<bool, std::int64_t, double, std::string, std::vector<double>>;

struct ParamEntry {
  ParamValue value;
  SourceLocation where;
  mutable bool queried = false;
};

// The schema of a section or a plug-in: one ParamSpecRecord per key.
struct ParamSchema {
  std::string owner;  // e.g. `basis "sh"` or `section [transport]`, used in messages
  std::vector<ParamSpecRecord> specs;

  const ParamSpecRecord* find(const std::string& key) const;
};

class Params {
 public:
  Params() = default;
  Params(SourceLocation section_location) : section_(std::move(section_location)) {}

  void set(const std::string& key, ParamValue value, SourceLocation where = {});
  bool has(const std::string& key) const { return entries_.count(key) != 0; }
  const SourceLocation& location() const { return section_; }
  const SourceLocation& location(const std::string& key) const;
  const std::map<std::string, ParamEntry>& entries() const { return entries_; }

  // Checks every key against the schema: unknown keys (with a did-you-mean),
  // wrong types, out-of-range values and unknown choices throw prt::Error with
  // the key's source location. Fills in defaults for keys not given.
  void validate(const ParamSchema& schema);

  // Typed getters. The key must be in the validated schema or have been set.
  bool get_bool(const std::string& key) const;
  std::int64_t get_int(const std::string& key) const;
  double get_real(const std::string& key) const;
  std::string get_string(const std::string& key) const;
  std::vector<double> get_reals(const std::string& key) const;

  // Throws a located error about `key` (used by plug-ins for checks the
  // schema cannot express, e.g. two parameters that exclude each other).
  [[noreturn]] void fail(const std::string& key, const std::string& message) const;

  // "key = value" pairs, one per line, for bake-file metadata.
  std::string describe() const;

 private:
  const ParamEntry& entry(const std::string& key) const;
  SourceLocation section_;
  std::map<std::string, ParamEntry> entries_;
};

// Levenshtein distance; used for did-you-mean suggestions.
std::size_t edit_distance(const std::string& a, const std::string& b);

// The closest candidate within a small edit distance, or "" if none is close.
std::string closest_match(const std::string& word, const std::vector<std::string>& candidates);

// The values a choice parameter allows, in the schema's order (its
// `choices`, "a|b|c"); empty for any other parameter.
std::vector<std::string> choices_of(const ParamSpecRecord& spec);

// The one parser of parameter values: a value written as in a scene file
// (true, 12, 0.5, [1, 2], "text") is typed exactly as the scene parser types
// it; anything TOML does not read as one value (a bare word such as
// per-cluster) is a string. Used for the command line, sweeps and schema
// defaults alike.
ParamValue parse_value(const std::string& text);
// "key=value" (command line, --bases entries) into `params`, located at `where`.
void parse_assignment(const std::string& text, const SourceLocation& where, Params& params);

}  // namespace prt
