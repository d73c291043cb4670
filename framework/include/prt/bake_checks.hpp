// Checks that a bake read from its file fits the scene, plug-ins and inputs
// that use it.
#pragma once
#include <string>
#include <vector>

#include "prt/bake_file.hpp"
#include "prt/registry.hpp"
#include "prt/rendered_metric.hpp"
#include "prt/scene.hpp"

namespace prt {

// Throws unless `transfer` encodes the bake's transfer: one row per vertex,
// valid indices, the bake's coefficients per vertex (and finite values
// when `finite`); `what` leads the message.
void check_encoding(const BakeData& data, const CompressedTransfer& transfer,
                    const std::string& what, bool finite = true);

// Checks that `data` was baked with the scene's bases, material and parameters.
void check_bake_matches(const BakeData& data, const SceneSpec& scene);
// Throws unless the bake's transfer has one column per basis coefficient (per
// exit-basis row for glossy transfer): a file's shape must fit its plug-ins.
void check_bake_dimension(const BakeData& data, const Basis& basis);

// Checks a bake's plug-in records against the plug-ins of this process:
// each record's parameters against its plug-in's schema (names, types,
// ranges), the bases' sizes against the transfer's columns and exit rows,
// and the compressed arrays against what the compressor so configured makes
// (Compressor::check_encoding). Throws "FILE: bad bake file: ..." naming the
// record; returns the records whose plug-in is not installed (not checked).
std::vector<std::string> check_bake_records(const std::string& file, const BakeData& data,
                                            PluginRegistry& registry);

// The rendered metric of a bake read from its file (made from its plug-in
// records and saved states).
RenderedMetric rendered_metric(const BakeData& data, PluginRegistry& registry);

}  // namespace prt
