#include "prt/params.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace prt {

const char* to_string(PluginKind kind) {
  switch (kind) {
    case PluginKind::basis:
      return "basis";
    case PluginKind::compressor:
      return "compressor";
    case PluginKind::renderer:
      return "renderer";
  }
  return "unknown";
}

const char* to_string(ParamType type) {
  switch (type) {
    case ParamType::boolean:
      return "bool";
    case ParamType::integer:
      return "integer";
    case ParamType::real:
      return "real";
    case ParamType::string:
      return "string";
    case ParamType::reals:
      return "list of reals";
    case ParamType::path:
      return "path";
  }
  return "unknown";
}

const ParamSpecRecord* ParamSchema::find(const std::string& key) const {
  for (const auto& spec : specs)
    if (key == spec.name) return &spec;
  return nullptr;
}

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1])});
      diagonal = above;
    }
  }
  return row[b.size()];
}

std::string closest_match(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_distance = std::max<std::size_t>(2, word.size() / 3) + 1;
  for (const auto& c : candidates) {
    const std::size_t d = edit_distance(word, c);
    if (d < best_distance) best_distance = d, best = c;
  }
  return best;
}

namespace {

std::string join(const std::vector<std::string>& items, const std::string& separator) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? separator : "") + items[i];
  return out;
}

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::stringstream stream(text);
  for (std::string part; std::getline(stream, part, separator);) parts.push_back(part);
  return parts;
}

std::string describe_value(const ParamValue& value) {
  return std::visit(
      [](const auto& v) -> std::string {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, bool>)
          return v ? "true" : "false";
        else if constexpr (std::is_same_v<T, std::int64_t>)
          return std::to_string(v);
        else if constexpr (std::is_same_v<T, double>) {
          std::ostringstream s;
          s.precision(17);
          s << v;
          return s.str();
        } else if constexpr (std::is_same_v<T, std::string>)
          return "\"" + v + "\"";
        else {
          std::vector<std::string> items;
          for (double x : v) items.push_back(describe_value(ParamValue(x)));
          std::string list = "[";  // appends: GCC 12 warns falsely on "[" + std::string
          return list.append(join(items, ", ")).append("]");
        }
      },
      value);
}

const char* value_type_name(const ParamValue& value) {
  static const char* names[] = {"bool", "integer", "real", "string", "list"};
  return names[value.index()];
}

// Parses a schema's textual default into a value of the spec's type.
ParamValue parse_default(const ParamSpecRecord& spec) {
  const std::string text = spec.default_value;
  if (spec.type == ParamType::string || spec.type == ParamType::path) return text;
  // A list default is written "0.1,0.3" in the schema: the parser reads [0.1,0.3].
  ParamValue value = parse_value(spec.type == ParamType::reals ? "[" + text + "]" : text);
  if (auto* i = std::get_if<std::int64_t>(&value); i && spec.type == ParamType::real)
    value = static_cast<double>(*i);
  if (auto* list = std::get_if<std::vector<double>>(&value);
      list && list->size() == 1 && spec.list_length > 1)
    list->resize(spec.list_length, (*list)[0]);
  return value;
}

std::string range_text(const ParamSpecRecord& spec) {
  char text[96];
  std::snprintf(text, sizeof text, "[%.10g, %.10g]", spec.min, spec.max);
  return text;
}

}  // namespace

std::vector<std::string> choices_of(const ParamSpecRecord& spec) {
  return split(spec.choices, '|');
}

void Params::set(const std::string& key, ParamValue value, SourceLocation where) {
  if (where.file.empty()) where = section_;
  entries_[key] = ParamEntry{std::move(value), std::move(where), false};
}

const SourceLocation& Params::location(const std::string& key) const {
  auto it = entries_.find(key);
  return it == entries_.end() ? section_ : it->second.where;
}

// "an integer", "a real": the article a type name takes.
static std::string article(const std::string& noun) {
  return noun.find_first_of("aeiou") == 0 ? "an " : "a ";
}

void Params::fail(const std::string& key, const std::string& message) const {
  // The key leads, so a message read away from its scene still says which one.
  throw Error(location(key), "parameter \"" + key + "\": " + message);
}

namespace {

// A string among its spec's choices (when it has any).
void check_choice(const ParamSpecRecord& spec, const std::string& what, const ParamEntry& entry) {
  const auto choices = choices_of(spec);
  if (choices.empty()) return;
  const std::string& text = std::get<std::string>(entry.value);
  if (std::find(choices.begin(), choices.end(), text) != choices.end()) return;
  std::string message = what + " = \"" + text + "\" is not one of: " + join(choices, ", ");
  const std::string suggestion = closest_match(text, choices);
  if (!suggestion.empty()) message += " (did you mean \"" + suggestion + "\"?)";
  throw Error(entry.where, message);
}

// Type, range and choice of one value (given, or the schema's default); a
// whole number for a real becomes a real, one number for a list a list.
void check_value(const ParamSchema& schema, const std::string& key, ParamEntry& entry) {
  const ParamSpecRecord* spec = schema.find(key);
  if (!spec) {
    std::vector<std::string> valid;
    for (const auto& s : schema.specs) valid.push_back(s.name);
    std::string message =
        schema.owner + ": unknown parameter \"" + elide(key) + "\"; " +
        (valid.empty() ? std::string("it takes no parameters") : "valid: " + join(valid, ", "));
    const std::string suggestion = closest_match(key, valid);
    if (!suggestion.empty()) message += " (did you mean \"" + suggestion + "\"?)";
    throw Error(entry.where, message);
  }
  const std::string what = schema.owner + ": parameter \"" + key + "\"";
  auto wrong_type = [&] {
    throw Error(entry.where, what + " must be " +
                                 (spec->type == ParamType::reals
                                      ? std::string("a number or a list of ") +
                                            std::to_string(spec->list_length) + " numbers"
                                      : article(to_string(spec->type)) + to_string(spec->type)) +
                                 ", got " + value_type_name(entry.value) + " " +
                                 describe_value(entry.value));
  };
  auto check_range = [&](double x) {
    if (!std::isfinite(x) || x < spec->min || x > spec->max)
      throw Error(entry.where, what + " = " + describe_value(entry.value) + " is out of range " +
                                   range_text(*spec));
  };
  switch (spec->type) {
    case ParamType::boolean:
      if (!std::holds_alternative<bool>(entry.value)) wrong_type();
      break;
    case ParamType::integer:
      if (!std::holds_alternative<std::int64_t>(entry.value)) wrong_type();
      check_range(static_cast<double>(std::get<std::int64_t>(entry.value)));
      break;
    case ParamType::real:
      if (auto* i = std::get_if<std::int64_t>(&entry.value))
        entry.value = static_cast<double>(*i);  // TOML "1" for a real is fine
      if (!std::holds_alternative<double>(entry.value)) wrong_type();
      check_range(std::get<double>(entry.value));
      break;
    case ParamType::reals: {
      if (auto* i = std::get_if<std::int64_t>(&entry.value)) entry.value = static_cast<double>(*i);
      if (auto* d = std::get_if<double>(&entry.value))
        entry.value = std::vector<double>(std::max<std::uint32_t>(spec->list_length, 1), *d);
      auto* list = std::get_if<std::vector<double>>(&entry.value);
      if (!list) wrong_type();
      if (spec->list_length && list->size() != spec->list_length) wrong_type();
      for (double x : *list) check_range(x);
      break;
    }
    case ParamType::string:
    case ParamType::path:
      if (!std::holds_alternative<std::string>(entry.value)) wrong_type();
      check_choice(*spec, what, entry);
      break;
  }
}

}  // namespace

void Params::validate(const ParamSchema& schema) {
  for (auto& [key, entry] : entries_) check_value(schema, key, entry);
  for (const auto& spec : schema.specs) {
    if (entries_.count(spec.name)) continue;
    if (spec.required)
      throw Error(section_, schema.owner + ": missing required parameter \"" +
                                std::string(spec.name) + "\" (" + spec.help + ")");
    if (spec.default_value[0] != '\0' || spec.type == ParamType::string ||
        spec.type == ParamType::path) {
      ParamEntry entry{parse_default(spec), section_, false};
      if (spec.default_value[0] != '\0') {  // an empty string default means "not given"
        try {
          check_value(schema, spec.name, entry);
        } catch (const Error& e) {
          throw Error(std::string(e.what()) + " (this is the schema's own default: a bug in " +
                      schema.owner + ")");
        }
      }
      entries_[spec.name] = std::move(entry);
    }
  }
}

const ParamEntry& Params::entry(const std::string& key) const {
  auto it = entries_.find(key);
  if (it == entries_.end()) throw Error(section_, "parameter \"" + key + "\" has no value");
  it->second.queried = true;
  return it->second;
}

bool Params::get_bool(const std::string& key) const {
  return std::get<bool>(entry(key).value);
}

std::int64_t Params::get_int(const std::string& key) const {
  return std::get<std::int64_t>(entry(key).value);
}

double Params::get_real(const std::string& key) const {
  const auto& value = entry(key).value;
  if (auto* i = std::get_if<std::int64_t>(&value)) return static_cast<double>(*i);
  return std::get<double>(value);
}

std::string Params::get_string(const std::string& key) const {
  return std::get<std::string>(entry(key).value);
}

std::vector<double> Params::get_reals(const std::string& key) const {
  return std::get<std::vector<double>>(entry(key).value);
}

std::string Params::describe() const {
  std::string out;
  for (const auto& [key, entry] : entries_) out += key + " = " + describe_value(entry.value) + "\n";
  return out;
}

}  // namespace prt
