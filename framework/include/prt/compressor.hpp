// The compressor interface: TransferSignal -> CompressedTransfer.
#pragma once
#include "prt/plugin.hpp"
#include "prt/transfer.hpp"

namespace prt {

class Compressor : public PluginObject {
 public:
  static constexpr PluginKind plugin_kind = PluginKind::compressor;
  virtual CompressedTransfer encode(const TransferSignal& signal) const = 0;
};

}  // namespace prt
