// A scene's text as toml++ may read it (ASCII only, same meaning): see
// scene_ascii.cpp.
#pragma once
#include <filesystem>
#include <string>

namespace prt {

// Throws prt::Error located in `file` at the first byte toml++ must not see.
std::string ascii_scene_text(const std::string& text, const std::filesystem::path& file);

}  // namespace prt
