// What the bake's stages keep in a checkpoint besides rows of a transfer: a
// fitted basis's state and the metrics of the stages done.
#pragma once
#include <functional>
#include <map>
#include <memory>
#include <string>

namespace prt {

class Basis;
class CheckpointStore;
struct FitData;

// Written after the basis state's parts, so that it marks the basis kept.
inline constexpr const char* kFittedBasisMarker = "fitted-basis";

// One part per matrix, under "basis_state.".
void keep_basis_state(const CheckpointStore& store, const Basis& basis);
// A fresh basis made by `make`, with the state kept in `store` loaded.
std::shared_ptr<const Basis> kept_basis(const CheckpointStore& store,
                                        const std::function<std::shared_ptr<Basis>()>& make);
// The state, then the marker (naming the plug-in) that says it is whole.
void keep_fitted_basis(const CheckpointStore& store, const Basis& basis, const std::string& name);
// A fresh basis made by `make`, fitted to `data`, and kept in `keep_in`
// under `name`'s marker unless null.
std::shared_ptr<const Basis> fit_fresh_basis(const std::function<std::shared_ptr<Basis>()>& make,
                                             const std::string& name, const FitData& data,
                                             const CheckpointStore* keep_in);

// A line "name value" per metric, exact to the last bit.
std::string metrics_text(const std::map<std::string, double>& metrics);
void read_metrics(const std::string& text, std::map<std::string, double>& metrics);

}  // namespace prt
