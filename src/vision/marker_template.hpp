// The last word on a decoded marker: how well the whole marker (hole, coded slices, black
// ring, white ring) as its reading says it is printed, blurred as the camera blurs it,
// matches the grey levels around the blob. The decoder's tests each read one feature on
// one circle; a letter or digit printed on the floor (an "e" reads as 6UCP ID 8, a "7" as
// ID 7) can pass each of them, but not all of the marker at once.
#pragma once

#include <opencv2/core.hpp>

#include <array>
#include <vector>

#include "vision/blob_detector.hpp"
#include "vision/marker_family.hpp"

namespace rilbed::vision {

/// Knobs of the template check.
struct MarkerTemplateConfig {
  /// Least correlation of the grey levels with the best-blurred ideal marker. On the
  /// stress set's tuning seeds 99.5 % of the markers found read 0.93 or more (the least
  /// 0.85, smeared by motion blur, which the isotropic blur models only approximate);
  /// the printed letters and digits that passed every other test read 0.78-0.90.
  /// Lower keeps more heavily blurred markers and lets more lookalikes through.
  double min_correlation = 0.92;
  /// Largest misfit of the black ring in any sector of 22.5 degrees: the mean squared
  /// residual of the grey levels on the ring's three circles against the best-blurred
  /// model (mapped to grey levels by the whole marker's least-squares gain and offset),
  /// over the model's mean squared signal across the whole marker. The correlation is one
  /// figure for the whole marker, so a local flaw averages away in it; a printed "e",
  /// which reads as ID 8, has an opening in its ring. On the stress set's tuning seeds
  /// the true markers' worst sectors scored under 1.2 in 99.9 % of cases (1.9 at most,
  /// small and smeared), the lookalikes that reached the decoder 1.1-5.3, most above 3.
  /// A light cable across a marker's ring scores about 1: lowering this to 0.9 would
  /// catch it but lose 0.4 % of the true markers. A large value turns the test off.
  double max_black_ring_misfit = 1.5;
};

/// How the grey levels around a blob fit a marker's model (MarkerTemplates::fit).
struct TemplateFit {
  /// Pearson correlation with the best-blurred model, in [-1, 1]; -1 when it could not
  /// be measured (too little of the marker inside the image, flat grey levels, an ID not
  /// listed).
  double correlation = -1.0;
  /// The worst sector's misfit of the black ring (MarkerTemplateConfig::max_black_ring_misfit),
  /// in the best-correlated model; 0 for a perfect fit.
  double black_ring_misfit = 0.0;
};

/// Ideal markers of a family's IDs, each rendered once, blurred to several strengths
/// and sampled on a polar grid (what correlation() compares with). An ID is rendered
/// when first asked for (about a millisecond; a 14ucp family has 2,048 IDs, most never
/// seen); after that correlation() costs 13 circle reads of 64 points and a few dot
/// products. Not thread-safe (the renders are cached); one per tracker.
class MarkerTemplates {
 public:
  MarkerTemplates(const MarkerFamily& family, const std::vector<int>& ids, MarkerTemplateConfig config = {});

  /// Pearson correlation, in [-1, 1], of the grey levels of `grey` (8-bit) sampled on
  /// the polar grid of the marker whose dark disc is `blob` (centre and shape) and whose
  /// key slice's bisector lies at `key_angle_rad` in the shape's unit-circle frame (as
  /// CodeMatch::key_angle_rad), with marker `id` blurred at each strength; the best.
  /// A marker at the frame's edge is compared on the circles that lie inside (at least
  /// out to the middle of its white ring). -1 when not even those do, or `id` is not one
  /// of the constructor's.
  double correlation(const cv::Mat& grey, const Blob& blob, int id, double key_angle_rad) const {
    return fit(grey, blob, id, key_angle_rad).correlation;
  }

  /// The correlation, and how well the black ring fits sector by sector.
  TemplateFit fit(const cv::Mat& grey, const Blob& blob, int id, double key_angle_rad) const;

  /// fit()'s correlation at least config's min_correlation, and its black ring's misfit
  /// at most config's max_black_ring_misfit.
  bool matches(const cv::Mat& grey, const Blob& blob, int id, double key_angle_rad) const {
    const TemplateFit f = fit(grey, blob, id, key_angle_rad);
    return f.correlation >= config_.min_correlation && f.black_ring_misfit <= config_.max_black_ring_misfit;
  }

  const MarkerTemplateConfig& config() const { return config_; }

  /// One ideal marker at one blur strength: its grey levels on the polar grid
  /// (radius-major, 64 angles per circle), and the sums of the levels and of their squares
  /// over the first c circles (prefix_sum[c]), which fit() would otherwise add up again
  /// for every blob. (Public only for the file's own helpers.)
  struct Model {
    std::vector<float> levels;
    std::array<double, 14> prefix_sum{}, prefix_sum_sq{};
  };

 private:
  // Per blur strength.
  using Models = std::vector<Model>;
  const Models& models_of(std::size_t index) const;

  MarkerFamily family_;
  MarkerTemplateConfig config_;
  std::vector<int> ids_;
  mutable std::vector<Models> models_;  // per ID; empty until first asked for
};

}  // namespace rilbed::vision
