// Finds a marker's whole dark disc from a fragment of it. On a small marker under heavy
// blur the white key slice and white data slices bleed into the thin black ring, and the
// dark region the blob detector fills at its local threshold may be one lobe of the disc
// (a third to a half of it, its centre a quarter of the marker's diameter off). Neither
// the blob nor an edge fit started from it finds the outline, though the rings are plain
// to see. The search tries centres around the fragment and radii larger than it, and
// keeps the circle with the most contrast between where the black ring and the white ring
// would lie: a first guess for the edge fit (fit_disc_edges), which decides.
#pragma once

#include <opencv2/core.hpp>

#include <optional>

#include "vision/blob_detector.hpp"

namespace rilbed::vision {

/// Knobs of the ring search. Its cost is one ring score (16 pixel reads on 8 rays) per
/// centre and radius tried, pi * (max_offset / centre_step)^2 (about 38) centres for each
/// of the radii, then up to 27 scores on 16 rays around the best: about 250 scores,
/// 5 microseconds.
struct RingSearchConfig {
  /// Fragments larger than this (the diameter of a circle of their area, pixels) are not
  /// searched: a marker whose lobe is this large has rings wide enough that the blur of
  /// a camera in focus does not break its disc. The lobes that lose 24-32 px markers are
  /// 9-15 px across; a 32 px marker's whole disc is 25 px. Larger costs more per frame on
  /// textured floors, where most of the fragments searched are the floor's own.
  double max_fragment_diameter_px = 24.0;
  /// Disc radii tried, as multiples of the fragment's own (that of a circle of its
  /// area): from min_scale to max_scale in steps of scale_step. The lobes that lose a
  /// 24-32 px marker are 0.5-0.75 of its disc across.
  double min_scale = 1.0;
  double max_scale = 2.05;
  double scale_step = 0.2;
  /// Centres tried lie on a grid spaced this fraction of the radius tried (at least a
  /// pixel) within max_offset of that radius from the fragment's centroid; around the
  /// best, every pixel within one spacing is tried. The edge fit that follows corrects a
  /// guess within about a quarter of the radius.
  double centre_step = 0.2;
  double max_offset = 0.7;
  /// Least mean difference, over the 16 rays, between the white ring's middle and the
  /// black ring's (grey levels) for the best circle to be reported. The decoder asks for
  /// more (DecoderConfig::min_ring_contrast); this only spares the edge fit hopeless work.
  double min_ring_contrast = 12.0;
};

/// The disc (centre and radius, as a circular Blob with `fragment`'s threshold) whose
/// rings contrast most around `fragment` in the 8-bit grey image, or nothing when no
/// circle tried lies inside the image or shows min_ring_contrast.
std::optional<Blob> search_ring(const cv::Mat& grey, const Blob& fragment, const RingSearchConfig& config = {});

}  // namespace rilbed::vision
