#include "kit.hpp"

#include <filesystem>

namespace prt::conformance {

bool Kit::expect(bool ok, const std::string& expression, const char* file, int line) {
  if (ok) return true;
  std::string message = std::filesystem::path(file).filename().string() + ":" +
                        std::to_string(line) + ": failed: " + expression;
  for (const auto& note : notes_) message += "\n  with: " + note;
  failures.push_back(std::move(message));
  return false;
}

bool Kit::expect_less(double a, double b, const char* a_text, const char* b_text, const char* file,
                      int line) {
  std::ostringstream text;
  text << a_text << " < " << b_text << " (" << a << " < " << b << ")";
  return expect(a < b, text.str(), file, line);
}

bool Kit::expect_at_most(double measured, double bound, const char* measured_text,
                         const char* bound_text, const char* file, int line) {
  std::ostringstream text;
  text.precision(6);
  text << measured_text << " <= " << bound_text << ": measured " << measured
       << ", expected at most " << bound;
  return expect(measured <= bound, text.str(), file, line);  // NaN fails
}

bool Kit::expect_equal(double measured, double expected, const char* measured_text,
                       const char* expected_text, const char* file, int line) {
  std::ostringstream text;
  text << measured_text << " == " << expected_text << ": measured " << measured << ", expected "
       << expected;
  return expect(measured == expected, text.str(), file, line);
}

Kit::Note::Note(Kit& kit, std::string text) : kit_(kit) {
  kit_.notes_.push_back(std::move(text));
}

Kit::Note::~Note() {
  kit_.notes_.pop_back();
}

const std::vector<Check>& checks(PluginKind kind) {
  static const std::vector<Check> basis = basis_checks();
  static const std::vector<Check> compressor = compressor_checks();
  static const std::vector<Check> renderer = renderer_checks();
  static const std::vector<Check> none;
  return kind == PluginKind::basis        ? basis
         : kind == PluginKind::compressor ? compressor
         : kind == PluginKind::renderer   ? renderer
                                          : none;
}

std::vector<std::string> run_check(const Check& check, PluginRegistry& registry,
                                   const std::string& plugin) {
  Kit kit(registry, plugin);
  try {
    check.run(kit);
  } catch (const Abort&) {
    // the failure that stopped it is recorded
  } catch (const std::exception& e) {
    kit.failures.push_back(std::string("unexpected exception: ") + e.what());
  } catch (...) {
    kit.failures.push_back("unexpected exception of unknown type");
  }
  return kit.failures;
}

}  // namespace prt::conformance
