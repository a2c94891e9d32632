// Re-finds a tracked marker's dark disc from its outline alone: along rows and columns
// across the outline predicted from the last frame it finds where the grey level crosses
// the marker's own threshold, and an ellipse fitted to those crossings gives the new
// centre and shape. It reads a few pixels per crossing instead of filling the disc,
// which is what makes a tracked frame a small fraction of a full-frame search. When the prediction is too
// far off (or the marker is not there), the fit says so and the caller falls back to
// the blob detector's fill.
#pragma once

#include <opencv2/core.hpp>

#include <optional>

#include "vision/blob_detector.hpp"

namespace rilbed::vision {

/// Knobs of the edge fit.
struct DiscEdgeFitConfig {
  /// Rows, and as many columns, across the disc; each gives two crossings (at most 32).
  /// 4 (the default) gives a tracked centre within about 0.02 px RMS of the truth on the
  /// benchmark's 32 px markers.
  /// More steadies the centre (errors average as 1/sqrt(crossings)) at a linear cost of
  /// about 5 pixel reads per crossing.
  int lines = 4;
  /// How far along its row or column each crossing is looked for, inwards and outwards
  /// from the predicted outline, as a fraction of the disc's radius. The black ring is 0.29 of
  /// it wide and the white ring 0.28, so a larger reach would run into the code or off
  /// the marker; a prediction off by more than this falls back to the fill.
  double reach = 0.26;
  /// Least fraction of the crossings looked for that must be found.
  double min_edge_fraction = 0.85;
  /// Largest RMS distance of the crossings from the fitted ellipse, as a fraction of its
  /// radius. A clean disc fits within about 0.02 and a square gives about 0.05; a disc
  /// cut by another object or a crossing on the code (prediction off) does not fit.
  double max_residual = 0.04;
  /// Largest change of the disc's area from the prediction's, as a fraction.
  double max_area_change = 0.3;
  /// Largest ratio of the ellipse's axes (as BlobDetectorConfig::max_axis_ratio).
  double max_axis_ratio = 1.8;
  /// Fit only the centre and the size, keeping the predicted outline's orientation and
  /// eccentricity: 3 unknowns instead of the ellipse's 5, so fewer crossings pin it
  /// down and the solve is cheaper. For a marker whose outline was fitted in full a few
  /// frames ago: its shape changes slowly as it crosses the field (perspective, lens),
  /// its place every frame.
  bool keep_shape = false;
  /// Crossings that may be dropped as lying on something across the rim rather than on
  /// the disc's outline: a light cable over the black ring's edge moves the crossings
  /// under it inwards, and an ellipse fitted through them (or the fill's moments) moves
  /// the centre towards the far side, which turns the heading read from it. While the
  /// crossing farthest inside the ellipse lies deeper than outlier_residual, it is
  /// dropped and the ellipse fitted again, at most this many times (the fit must still
  /// pass max_residual on the rest). Only inside: light on the rim moves a crossing
  /// inwards, and an ellipse pulled in by a covered arc bulges out elsewhere, where the
  /// crossings then lie outside it though they are the disc's. Costs a pass over the
  /// crossings per drop and an ellipse fit; nothing when no crossing lies that far.
  /// 0 turns it off. Not with keep_shape.
  int max_outliers = 0;
  /// How far inside the ellipse (a fraction of its radius) a crossing is an outlier. A
  /// clean disc's crossings lie within about 0.05 of it, a blurred one's partly beyond.
  /// On the stress set's tuning seeds 0.08 left the centres of markers under cables
  /// 0.27 px RMS off where 0.06 leaves 0.21 px, and 0.05 dropped crossings of clean,
  /// blurred 24-32 px markers (a heading 6.4 degrees off, against 4.0 at 0.06).
  double outlier_residual = 0.06;
};

/// What the edge fit found.
struct DiscEdgeFit {
  /// The disc, as the blob detector would report it (centre, shape, threshold; the
  /// filled area is the ellipse's).
  Blob blob;
  /// Mean grey level of the black ring and of the white ring, read on the rows of the
  /// crossings, inside and outside each.
  double black_level = 0.0;
  double white_level = 0.0;
  /// Fraction of the white-ring reads brighter than the midpoint of the two levels.
  double white_fraction = 0.0;
  /// RMS distance of the crossings from the fitted outline, as a fraction of its radius
  /// (at most DiscEdgeFitConfig::max_residual). With keep_shape, a value that grows says
  /// the shape kept no longer matches the disc's.
  double residual = 0.0;
  /// Crossings dropped as outliers (DiscEdgeFitConfig::max_outliers); the residual is
  /// that of the rest.
  int outliers = 0;
};

/// Fits the outline of the disc predicted by `predicted` (its centre and shape; see
/// Blob) in the 8-bit grey image, with `threshold_grey` the grey level between the
/// marker's black and white rings. Returns nothing when the marker is not close enough
/// to the prediction, not whole inside the image, or not a clean ellipse.
std::optional<DiscEdgeFit> fit_disc_edges(const cv::Mat& grey, const Blob& predicted, double threshold_grey,
                                          const DiscEdgeFitConfig& config = {});

/// Asks the CPU to start loading (into its L2 cache) the pixels fit_disc_edges will read
/// for `predicted` (the rows of the predicted disc, as wide as the fit's reads; the few
/// pixels its walks read beyond the disc's rows are left to be fetched on demand),
/// without waiting for them. A camera frame is not in the CPU's near caches when it
/// arrives and the fit's reads are scattered, so each would wait for memory in turn;
/// prefetching the next marker's area while fitting the current one overlaps those
/// waits. Does nothing outside the image; changes nothing.
void prefetch_disc_area(const cv::Mat& grey, const Blob& predicted, const DiscEdgeFitConfig& config = {});

/// Reads one byte of every cache line of the same area now, with plain loads, and
/// returns them OR-ed (use it, so that the loads are kept). For the first markers of a
/// frame: their pixels are needed at once, and the CPU keeps many independent loads in
/// flight where it drops most of a burst of prefetch hints issued with nothing else
/// waiting on memory (on this project's machine an 8-marker tracked frame took a third
/// longer with hints alone).
std::uint8_t load_disc_area(const cv::Mat& grey, const Blob& predicted, const DiscEdgeFitConfig& config = {});

}  // namespace rilbed::vision
