// Checks an environment map's declared size against its file before a decoder
// allocates for it: stb fills missing Radiance pixels with zeros without a
// word, and an EXR header may declare any resolution.
#pragma once
#include <cstdint>
#include <filesystem>

namespace prt {

// A Radiance .hdr: magic line, resolution, and every scanline present (the
// run-length structure is walked, nothing decoded). Throws prt::Error naming
// the file otherwise.
void check_radiance_file(const std::filesystem::path& file);

// An OpenEXR file: magic number, and every header attribute's declared size
// within the file (OpenEXR allocates it before reading).
void check_exr_file(const std::filesystem::path& file);

// Refuses a resolution that the file's size cannot plausibly encode (a
// compressed image holds at most 64x its size in half RGBA, beyond 4 Mpixels).
void check_image_resolution(const std::filesystem::path& file, std::int64_t width,
                            std::int64_t height);

}  // namespace prt
