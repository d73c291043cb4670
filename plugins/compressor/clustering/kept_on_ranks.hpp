// How the clustering loops keep a distributed state in a shared checkpoint:
// every rank writes its own parts (its shard's labels), then, once all have,
// rank 0 the parts every rank shares (means, models: the same everywhere),
// which name the others and so are written last.
#pragma once
#include <functional>
#include <string>

#include "prt/clustering.hpp"
#include "prt/error.hpp"
#include "prt/log.hpp"

namespace prt::clustering {

// False on every rank when any write failed: a full disk ends the keeping
// (on every rank alike, so their collectives stay in step), not the encode.
inline bool keep_on_ranks(const Rows& rows, const char* who, const std::function<void()>& own_parts,
                          const std::function<void()>& shared_parts) {
  const auto failed = [&](const std::function<void()>& write) {
    try {
      write();
      return false;
    } catch (const Error& e) {
      log_warning(std::string(who) + ": keeping its state failed, going on without: " + e.what());
      return true;
    }
  };
  if (rows.any(failed(own_parts))) return false;
  return !rows.any(rows.parts->first() && failed(shared_parts));
}

}  // namespace prt::clustering
