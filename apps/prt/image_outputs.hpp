// What `prt render --compare` writes beside its image, and the image metrics
// it prints: the error heat map with its colour bar, the signed error as
// OpenEXR, and the ground truth in the image's own format.
#pragma once
#include <filesystem>
#include <vector>

#include "prt/image.hpp"

namespace prt::cli {

struct ComparisonFiles {
  std::filesystem::path heat_map, signed_error, truth;
};

// out/bunny.png -> out/bunny.error.png, out/bunny.error.exr, out/bunny.truth.png
ComparisonFiles comparison_files(const std::filesystem::path& image);

// Each file refused now, as the image is, before any work.
void check_comparison_files(const ComparisonFiles& files,
                            const std::vector<std::filesystem::path>& inputs, bool force,
                            bool create_folder);

// Writes the three files and prints PSNR, SSIM and the heat map's scale.
void write_comparison(const Image& render, const Image& truth, float exposure,
                      const ComparisonFiles& files);

}  // namespace prt::cli
