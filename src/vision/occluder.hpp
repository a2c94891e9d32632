// Something lying across a marker: a cable, a wire, a pen. Where it crosses a white slice
// of the code it can read as black, and the marker as another ID (a grey cable over ID 5's
// third data slice reads ID 1). The decoder's own test of the white ring counts reads
// below the midpoint of the rings' levels, which a mid-grey cable over a blurred marker
// does not reach. This model asks instead for what a lying object makes: a band that dims
// the white ring against the ring's own level *and* goes on across the floor just beyond
// the marker, at the same place round it. A clean marker's ring may dim with blur or a
// shadow, and a textured floor varies, but not both at once at the same angles.
#pragma once

#include <opencv2/core.hpp>

#include "vision/blob_detector.hpp"

namespace rilbed::vision {

/// Knobs of the occluder model (find_band_across).
struct OccluderConfig {
  /// Find and decline markers that something lies across. Off reads them as if whole.
  bool enabled = true;
  /// A read of the white ring counts as covered when it lies this fraction of the ring
  /// contrast (white ring minus black ring) below the ring's own level (the upper quartile
  /// of its 64 reads). Lower catches fainter cables and declines more clean markers whose
  /// ring blur or a shadow dims in places. The cables that made wrong IDs on the stress
  /// set dipped 0.39-0.57 (the faintest over a marker of 35 grey levels' contrast); clean
  /// small blurred markers beside dark floor texture dip 0.2-0.4. On tuning seed 777
  /// (2,888 markers) this model declined 3 of 1,800 whole markers of 24 px and more and
  /// 13 of 360 at 20-24 px; 0.4 declined 1 and 1 but let a cable read ID 6 as 2.
  double ring_dip = 0.3;
  /// ...and the floor just beyond the marker (1.15-1.3 of its radius), within
  /// `max_shift_reads` of that angle, lies this fraction of the ring contrast away from
  /// the floor's own level (the median of its 64 reads), darker or lighter (the cables
  /// that made wrong IDs: 0.64-0.72).
  double floor_dip = 0.25;
  /// How far round the marker (reads of 64, 5.6 degrees each) the band may meet the floor
  /// from where it crossed the ring: a cable crossing at a slant meets the outer circle
  /// further round.
  int max_shift_reads = 4;
  /// Least run of covered ring reads (of 64) that makes a band: one read is noise.
  int min_band_reads = 2;
  /// Longest run that still makes a band: a cable is narrow beside a marker (a 3 mm cable
  /// over a 45 mm marker covers about 2 reads where it crosses square on); a ring dimmed
  /// over a long arc is a shadow, vignetting or a dark floor beside a blurred marker.
  int max_band_reads = 8;
  /// Longest run of floor reads (of 64, round the circle) off the floor's level that the
  /// band may meet there: a cable is narrow on the floor too, where the edge of a robot's
  /// dark top just beyond a marker, or a dark patch of floor, is off over a long arc.
  int max_floor_run_reads = 10;
  /// Least number of places (runs of covered ring reads, each with the floor beyond it
  /// covered) for a marker to count as lain across. A cable, a wire or a pen crosses the
  /// ring twice; a dark speck of the floor beside a small blurred marker dims its thin
  /// white ring and lies beyond it at one place. 1 also declines markers at a cable's end.
  int min_bands = 2;
};

/// What find_band_across found.
struct BandAcross {
  int bands = 0;        ///< runs of covered white-ring reads with the floor beyond them covered too
  bool across = false;  ///< at least OccluderConfig::min_bands of them: something lies across the marker
};

/// Looks for a band lying across the marker whose dark disc is `blob` (centre, shape),
/// with the rings' levels `black_level` and `white_level` (grey, as SampledSignal gives
/// them). Reads 64 points on the white ring and 2 x 64 on the floor beyond; a marker whose
/// surroundings leave the image is not judged (no band). `grey` is 8-bit.
BandAcross find_band_across(const cv::Mat& grey, const Blob& blob, double black_level, double white_level,
                            const OccluderConfig& config);

}  // namespace rilbed::vision
