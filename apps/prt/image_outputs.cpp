#include "image_outputs.hpp"

#include <cmath>
#include <cstdio>

#include "prt/error_image.hpp"
#include "prt/image_metrics.hpp"
#include "prt/output_file.hpp"

namespace prt::cli {

namespace fs = std::filesystem;

ComparisonFiles comparison_files(const fs::path& image) {
  const fs::path stem = image.parent_path() / image.stem();
  return {fs::path(stem.string() + ".error.png"), fs::path(stem.string() + ".error.exr"),
          fs::path(stem.string() + ".truth" + image.extension().string())};
}

void check_comparison_files(const ComparisonFiles& files, const std::vector<fs::path>& inputs,
                            bool force, bool create_folder) {
  check_output({files.heat_map, FileKind::png, "error image", create_folder}, inputs, force);
  check_output({files.signed_error, FileKind::exr, "error image", create_folder}, inputs, force);
  check_output({files.truth, files.truth.extension() == ".exr" ? FileKind::exr : FileKind::png,
                "ground-truth image", create_folder},
               inputs, force);
}

void write_comparison(const Image& render, const Image& truth, float exposure,
                      const ComparisonFiles& files) {
  const Image8 shown = display_image(render, exposure), expected = display_image(truth, exposure);
  const double peak_to_noise = psnr(shown, expected);
  std::printf(
      "image metrics as displayed (8-bit sRGB at exposure %g, the whole frame, the same "
      "background in both): PSNR %.2f dB, SSIM %.4f (scikit-image's definitions)\n",
      double(exposure), peak_to_noise, ssim(shown, expected));
  const ErrorHeatMap heat = error_heat_map(render, truth, exposure);
  write_png(heat.image, files.heat_map);
  write_exr(signed_difference(render, truth), files.signed_error);
  write_image(truth, files.truth, exposure);
  std::printf(
      "error images: %s (|error| x exposure, 1 = white; bar 0 to %.4g, the 99th percentile; "
      "peak %.4g), %s (render - truth, linear), ground truth %s\n",
      files.heat_map.string().c_str(), heat.top, heat.peak, files.signed_error.string().c_str(),
      files.truth.string().c_str());
}

}  // namespace prt::cli
