// The bake and view pipelines composed from a scene: the same code serves the
// CLI, the tests and the benchmarks. One header for all of them; each part
// has its own.
#pragma once
#include "prt/bake.hpp"
#include "prt/bake_checks.hpp"
#include "prt/bake_plan.hpp"
#include "prt/bake_stages.hpp"
#include "prt/ground_truth_render.hpp"
#include "prt/relighting.hpp"
#include "prt/run_options.hpp"
#include "prt/turning_light.hpp"
