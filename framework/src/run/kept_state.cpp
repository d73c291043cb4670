#include "kept_state.hpp"

#include <cstdio>
#include <sstream>

#include "prt/basis.hpp"
#include "prt/checkpoint.hpp"

namespace prt {

namespace {

constexpr const char* kBasisStatePrefix = "basis_state.";

void load_kept_basis_state(const CheckpointStore& store, Basis& basis) {
  const std::string prefix = kBasisStatePrefix;
  BasisState state;
  for (const auto& part : store.parts())
    if (part.rfind(prefix, 0) == 0)
      state.matrices[part.substr(prefix.size())] = store.load_doubles(part);
  basis.load(state);
}

}  // namespace

void keep_basis_state(const CheckpointStore& store, const Basis& basis) {
  for (const auto& [name, matrix] : basis.save().matrices)
    store.save(kBasisStatePrefix + name, matrix);
}

std::shared_ptr<const Basis> kept_basis(const CheckpointStore& store,
                                        const std::function<std::shared_ptr<Basis>()>& make) {
  std::shared_ptr<Basis> basis = make();
  load_kept_basis_state(store, *basis);
  return basis;
}

void keep_fitted_basis(const CheckpointStore& store, const Basis& basis, const std::string& name) {
  keep_basis_state(store, basis);
  store.save_text(kFittedBasisMarker, name);  // last: marks the basis kept
}

std::shared_ptr<const Basis> fit_fresh_basis(const std::function<std::shared_ptr<Basis>()>& make,
                                             const std::string& name, const FitData& data,
                                             const CheckpointStore* keep_in) {
  const std::shared_ptr<Basis> fitted = make();
  fitted->fit(data);
  if (keep_in) keep_fitted_basis(*keep_in, *fitted, name);
  return fitted;
}

std::string metrics_text(const std::map<std::string, double>& metrics) {
  std::string text;
  char line[256];
  for (const auto& [name, value] : metrics) {
    std::snprintf(line, sizeof line, "%s %.17g\n", name.c_str(), value);
    text += line;
  }
  return text;
}

void read_metrics(const std::string& text, std::map<std::string, double>& metrics) {
  std::istringstream in(text);
  std::string name;
  double value = 0;
  while (in >> name >> value) metrics[name] = value;
}

}  // namespace prt
