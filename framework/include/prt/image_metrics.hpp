// Image-quality metrics of a render against its reference as displayed: on
// the 8-bit sRGB images a PNG holds (prt::display_image), computed as
// scikit-image computes them, so a paper's numbers can be checked there
// (tests/integration/image_metrics.sh does, on fixed images).
#pragma once
#include "prt/image.hpp"

namespace prt {

// Peak signal-to-noise ratio in dB for a data range of 255 (infinite for
// identical images): skimage.metrics.peak_signal_noise_ratio.
double psnr(const Image8& a, const Image8& b);

// Mean structural similarity (Wang et al. 2004): Gaussian window of sigma
// 1.5 truncated at 3.5 sigma (11 x 11), K1 = 0.01, K2 = 0.03, population
// covariances, data range 255, averaged over the pixels at least 5 from the
// border and then over channels: skimage.metrics.structural_similarity with
// channel_axis=2, gaussian_weights=True, sigma=1.5,
// use_sample_covariance=False, data_range=255. Images need 11 x 11 pixels.
double ssim(const Image8& a, const Image8& b);

}  // namespace prt
