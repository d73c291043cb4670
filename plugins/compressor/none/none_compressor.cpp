// The exact "compression" (exact_form): a cluster per vertex whose mean is the
// vertex's transfer and no components, so nothing is lost.
#include <array>

#include "prt/compressor.hpp"
#include "prt/plugin.hpp"

namespace prt {

class NoCompression final : public Compressor {
 public:
  static constexpr const char* plugin_version = "1.0.0";
  static constexpr const char* plugin_description = "keeps the transfer exact (no compression)";
  static constexpr auto parameters() { return std::array<ParamSpecRecord, 0>{}; }

  explicit NoCompression(const Params&) {}

  bool exact() const override { return true; }

  // Its own exact form, or a basis's sparse approximation that replaced it.
  void check_encoding(const CompressedTransfer& c) const override {
    if (!c.sparse() && (c.components != 0 || c.clusters() != c.vertices()))
      throw Error("the encoding has " + std::to_string(c.clusters()) + " clusters and " +
                  std::to_string(c.components) +
                  " components; an exact form has a cluster per vertex and none");
  }

  CompressedTransfer encode(const TransferSignal& signal, const Mesh*) const override {
    CompressedTransfer c = exact_form(signal);
    c.compressor = "none";
    return c;
  }
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::NoCompression, "none")
