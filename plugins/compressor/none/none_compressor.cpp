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

  CompressedTransfer encode(const TransferSignal& signal, const Mesh*) const override {
    CompressedTransfer c = exact_form(signal);
    c.compressor = "none";
    return c;
  }
};

}  // namespace prt

PRT_EXPORT_PLUGIN(prt::NoCompression, "none")
