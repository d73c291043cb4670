// toml++, compiled into libprt with its internal assumptions checked.
//
// toml++ 3.3 marks what it believes impossible with TOML_ASSERT_ASSUME and
// TOML_UNREACHABLE, which a release build turns into __builtin_assume and
// __builtin_unreachable: malformed scenes reach several of them (fuzzing
// found a table header "[#", a stray '}' in an array, "0000------ 0,"), and
// reaching one is undefined behaviour. Here every such point throws instead,
// and prt reports the scene as malformed. Debian ships toml++ as a shared
// library built with those assumptions, so libprt uses the header-only form.
#pragma once

#include "prt/error.hpp"

namespace prt {
[[noreturn]] void toml_assumption_broken(const char* what);
}

#pragma push_macro("NDEBUG")
#undef NDEBUG
#undef TOML_HEADER_ONLY
#undef TOML_SHARED_LIB
#define TOML_HEADER_ONLY 1
#define TOML_ASSERT(expr) ((expr) ? static_cast<void>(0) : ::prt::toml_assumption_broken(#expr))
#include <toml++/impl/preprocessor.h>
#undef TOML_UNREACHABLE
#define TOML_UNREACHABLE ::prt::toml_assumption_broken("unreachable code")
#include <toml++/toml.h>
#pragma pop_macro("NDEBUG")
