// The conformance kit: the checks every plug-in of a kind must pass, as plain
// functions, so that the C++ kit (Catch2, one test case per check) and the
// Python kit (prt.testing, one pytest test per check) run the same code.
#pragma once
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "prt/plugin_record.hpp"
#include "prt/registry.hpp"

namespace prt::conformance {

// Thrown by KIT_REQUIRE to end a check after a failure it cannot go on from.
struct Abort {};

// What one check sees: the registry and the plug-in under test, and the
// failures it has found so far (each with the notes in scope).
class Kit {
 public:
  Kit(PluginRegistry& registry, std::string plugin)
      : registry(registry), plugin(std::move(plugin)) {}
  PluginRegistry& registry;
  const std::string plugin;
  std::vector<std::string> failures;

  // Records a failure unless `ok`; returns ok.
  bool expect(bool ok, const std::string& expression, const char* file, int line);
  // a < b, with both values in the failure's message.
  bool expect_less(double a, double b, const char* a_text, const char* b_text, const char* file,
                   int line);
  // measured <= bound: the failure says what was measured, the bound (the
  // tolerance the check allows) and both expressions.
  bool expect_at_most(double measured, double bound, const char* measured_text,
                      const char* bound_text, const char* file, int line);
  // measured == expected (counts and sizes), both values in the message.
  bool expect_equal(double measured, double expected, const char* measured_text,
                    const char* expected_text, const char* file, int line);

  // A note attached to every failure while it lives (Catch's INFO).
  class Note {
   public:
    Note(Kit& kit, std::string text);
    ~Note();
    Note(const Note&) = delete;
    Note& operator=(const Note&) = delete;

   private:
    Kit& kit_;
  };

 private:
  std::vector<std::string> notes_;
};

struct Check {
  std::string name;  // a sentence: what a passing plug-in does
  std::string tags;  // Catch2 tags, e.g. "[conformance][extremes]"
  std::function<void(Kit&)> run;
};

// The checks of a kind (basis, compressor or renderer).
const std::vector<Check>& checks(PluginKind kind);
std::vector<Check> basis_checks();
std::vector<Check> compressor_checks();
std::vector<Check> renderer_checks();

// Runs one check on `plugin` from `registry`: its failures, empty when it
// passes. An exception escaping the check is a failure too.
std::vector<std::string> run_check(const Check& check, PluginRegistry& registry,
                                   const std::string& plugin);

}  // namespace prt::conformance

#define KIT_CHECK(kit, ...) \
  (kit).expect(static_cast<bool>(__VA_ARGS__), #__VA_ARGS__, __FILE__, __LINE__)
#define KIT_CHECK_LESS(kit, a, b) (kit).expect_less((a), (b), #a, #b, __FILE__, __LINE__)
#define KIT_CHECK_AT_MOST(kit, measured, bound) \
  (kit).expect_at_most((measured), (bound), #measured, #bound, __FILE__, __LINE__)
#define KIT_CHECK_EQUAL(kit, measured, expected)                                              \
  (kit).expect_equal(static_cast<double>(measured), static_cast<double>(expected), #measured, \
                     #expected, __FILE__, __LINE__)
#define KIT_REQUIRE(kit, ...)                                         \
  if (!KIT_CHECK(kit, __VA_ARGS__)) throw ::prt::conformance::Abort { \
    }
#define KIT_CONCAT_(a, b) a##b
#define KIT_CONCAT(a, b) KIT_CONCAT_(a, b)
#define KIT_INFO(kit, stream)                                    \
  ::prt::conformance::Kit::Note KIT_CONCAT(kit_note_, __LINE__)( \
      kit, (std::ostringstream() << stream).str())
// The expression throws prt::Error (whose message holds `text`, if given).
#define KIT_CHECK_THROWS_WITH(kit, expression, text)                                            \
  do {                                                                                          \
    std::string kit_thrown_;                                                                    \
    bool kit_threw_ = false;                                                                    \
    try {                                                                                       \
      (void)(expression);                                                                       \
    } catch (const ::prt::Error& e) {                                                           \
      kit_threw_ = true;                                                                        \
      kit_thrown_ = e.what();                                                                   \
    }                                                                                           \
    (kit).expect(kit_threw_&& kit_thrown_.find(text) != std::string::npos,                      \
                 std::string(#expression " throws prt::Error mentioning \"") + text + "\"" +    \
                     (kit_threw_ ? " (it threw: " + kit_thrown_ + ")" : " (it did not throw)"), \
                 __FILE__, __LINE__);                                                           \
  } while (0)
#define KIT_REQUIRE_NOTHROW(kit, expression)                                                       \
  do {                                                                                             \
    try {                                                                                          \
      (void)(expression);                                                                          \
    } catch (const std::exception& e) {                                                            \
      (kit).expect(false, std::string(#expression " throws nothing (it threw: ") + e.what() + ")", \
                   __FILE__, __LINE__);                                                            \
      throw ::prt::conformance::Abort{};                                                           \
    }                                                                                              \
  } while (0)
