// Finds the dark, circular blobs that 6UCP markers make in a grey image: a local
// threshold (tile min/max, the local form of the paper's contrast stretch), a seeded
// sweep of row extents (a run-by-run flood fill for regions that are not disc-like), and
// shape tests on the region's outline. Each blob comes with a sub-pixel centroid and the
// ellipse that the marker's circle projects to.
#pragma once

#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace rilbed::vision {

/// Knobs of the blob detector. Sizes are of the whole marker (outer white ring) in
/// pixels, as they appear in the image.
struct BlobDetectorConfig {
  /// Smallest marker diameter looked for. Lower finds smaller markers but lets more
  /// clutter reach the decoder.
  double min_diameter_px = 18.0;
  /// Largest marker diameter looked for. Higher costs nothing per frame by itself, but
  /// markers much larger than 8 tiles (see tile_px) may lose local contrast inside.
  double max_diameter_px = 480.0;
  /// Side of the square tiles over which the local threshold is computed. Smaller adapts
  /// to steeper lighting changes; larger saves time and keeps big markers intact.
  int tile_px = 8;
  /// Least grey-level difference between the darkest and brightest pixel around a tile
  /// for its pixels to count as dark or bright. Lower accepts fainter markers and more
  /// noise-made fragments.
  int min_local_contrast = 24;
  /// The least local contrast is also at least this many times the floor's own
  /// contrast (the lower quartile of the local grey-level ranges, measured on each
  /// full-frame search), so that sensor noise does not count as contrast and flood the
  /// search with specks. Higher rejects more noise and loses faint markers sooner.
  double contrast_over_noise = 1.8;
  /// ...but never more than this many grey levels: a frame crowded with markers must
  /// not raise the bar to the markers' own contrast.
  int max_noise_contrast = 64;
  /// A neighbourhood of tiles whose darkest pixel is lighter than this fraction of its
  /// brightest holds no marker's black (printed black reflects a fifth or less of what
  /// white does) and is not searched. This keeps the floor beside a marker's white ring,
  /// darker than the ring but nowhere near black, from being filled as dark: on a light
  /// floor that was two thirds of all fills. Raise towards 1 for markers under heavy
  /// glare; 1 searches every tile with contrast.
  double max_black_to_white = 0.7;
  /// Rows between seed scan lines of a search; 0 picks a quarter of the smallest dark
  /// disc. Larger is faster and misses markers smaller than about 2 steps.
  int seed_row_step = 0;
  /// Largest mean relative deviation of the blob's chord lengths from those of an
  /// ellipse. A disc scores about 0.02, a square 0.2.
  double max_chord_error = 0.09;
  /// A region that passes every other test but whose chord error lies between
  /// max_chord_error and this is still reported, flagged Blob::doubtful, for the caller
  /// to confirm from the disc's outline (MarkerTracker re-fits it with fit_disc_edges and
  /// drops it when that fails). Heavy blur bleeds a marker's white key slice into its thin
  /// black ring, so the dark region of a small blurred marker has a notch where the fit
  /// of its outline, at the marker's own threshold, finds the whole ellipse. Costs an edge
  /// fit per such region; at most max_chord_error turns it off. Higher finds more
  /// blurred markers and hands more lookalikes to the decoder's and the template's tests.
  double max_doubtful_chord_error = 0.3;
  /// Largest ratio of the ellipse's axes (a marker viewed at 60 degrees gives 2).
  double max_axis_ratio = 1.8;
  /// Least fraction of the outline's outside neighbours that must be bright (above a
  /// valid local threshold). Rejects dark floor around a marker on a dark mat.
  double min_bright_outline = 0.9;
  /// Largest relative difference between the filled area and the ellipse's area.
  double max_area_error = 0.15;
};

/// One candidate marker: the filled dark disc enclosed by the marker's black ring.
struct Blob {
  /// Sub-pixel centroid of the filled disc, pixels (u right, v down).
  double u = 0.0;
  double v = 0.0;
  /// Affine map from the unit circle to the disc's outline: outline = centre + shape·p
  /// for |p| = 1. Symmetric (the polar decomposition's stretch). Pixels.
  cv::Matx22d shape = cv::Matx22d::eye();
  /// Local threshold (grey level) at the centre.
  double threshold = 0.0;
  /// Area of the filled disc in pixels.
  double filled_area_px = 0.0;
  /// Diameter of a circle of the same area as the disc, pixels.
  double disc_diameter_px() const;
  /// Its outline strays from an ellipse more than a clean disc's would (see
  /// BlobDetectorConfig::max_doubtful_chord_error): the centre and shape are only a
  /// first guess, to be confirmed from the outline before use.
  bool doubtful = false;
};

/// How many of `rays` rays from `blob`'s centre, spread evenly round its ellipse, cross a
/// pixel of `grey` (8-bit) brighter than halfway between the blob's rim (0.9 of its
/// radius) and what lies just outside it (1.25), between `from` and `to` times its radius
/// (fractions of the ellipse; nearest pixels, half a pixel apart). A
/// dark region that encloses a marker, such as a robot's dark top, has the marker's white
/// ring all round inside it; a marker's own disc has two black slices from its hole to its
/// rim, and dark floor specks little bright inside. Costs about rays x radius pixel reads.
int rays_crossing_bright(const cv::Mat& grey, const Blob& blob, int rays, double from, double to);

/// Why a dark region was not kept as a blob (BlobDetector::set_rejection_log).
enum class RegionRejection {
  kCut,            ///< the region touches the search window's border, or is larger than any marker
  kTooSmall,       ///< smaller than the least marker's disc
  kNotCompact,     ///< fills too little of its bounding box, or the box is too long, for an ellipse
  kDimOutline,     ///< too few of its outside neighbours are bright (min_bright_outline)
  kDegenerate,     ///< no area, or a covariance without two axes
  kElongated,      ///< axis ratio beyond max_axis_ratio
  kAreaMismatch,   ///< its area is not that of its moments' ellipse (max_area_error)
  kRaggedOutline,  ///< its chords stray from the ellipse beyond max_doubtful_chord_error
};

/// The name of a rejection ("cut", "too small", ...).
const char* rejection_name(RegionRejection why);

/// One region a full search filled and turned away, for finding out why a marker was missed.
struct RejectedRegion {
  double u = 0, v = 0;   ///< the centre of its bounding box (kCut: the seed), pixels
  double extent_px = 0;  ///< the longer side of its bounding box (kCut: 0)
  RegionRejection why = RegionRejection::kCut;
};

/// Detects marker blobs in 8-bit grey frames of one size. Keeps its scratch buffers
/// between calls (not thread-safe; one per camera).
class BlobDetector {
 public:
  explicit BlobDetector(BlobDetectorConfig config = {});

  /// Searches `roi` (clipped to the image) of the 8-bit single-channel image `grey`.
  /// Blobs touching the ROI's border are dropped (they may be cut).
  std::vector<Blob> detect(const cv::Mat& grey, cv::Rect roi);

  /// Like detect(grey, roi), but first looks for the one blob around `expected_px` (a
  /// tracked marker's predicted centre): it seeds a fill from the nearest dark pixel on
  /// that row and, if the result is a blob centred within its own radius of the
  /// prediction, returns it alone without scanning the rest of the ROI. This is the
  /// tracked path's saving: one fill instead of a search.
  /// With `threshold_grey` (the midpoint of the marker's black and white last seen), the
  /// first attempt uses that one threshold across the ROI instead of measuring local
  /// contrast: a tracked frame then costs one fill. The full local method is the fallback.
  std::vector<Blob> detect_near(const cv::Mat& grey, cv::Rect roi, cv::Point2d expected_px,
                                std::optional<double> threshold_grey = std::nullopt);

  /// The whole image.
  std::vector<Blob> detect(const cv::Mat& grey) { return detect(grey, cv::Rect(0, 0, grey.cols, grey.rows)); }

  /// Like detect(grey, roi), but every region is filled exactly, so that what a dark
  /// region encloses is searched as well: a marker's disc within the dark top of the robot
  /// that carries it (the top, itself a dark disc, is among the blobs returned when a
  /// seed lies on it). The quick sweep that detect() tries first takes in an enclosing
  /// region's inside whole and clears it; this costs an exact fill per region instead. A
  /// disc there is held to `min_bright_outline` in place of the config's: a marker's thin
  /// white ring between its black ring and a dark top, blurred, dips below the local
  /// threshold in places.
  /// With `seeds`, fills start only from the seed rows' well-dark pixels within it (each
  /// fill may still extend over all of roi): the middle of a robot's top, where its
  /// marker lies, so that the top's own dark rim around the marker is not filled for
  /// nothing.
  std::vector<Blob> detect_inside(const cv::Mat& grey, cv::Rect roi, double min_bright_outline,
                                  std::optional<cv::Rect> seeds = std::nullopt);

  const BlobDetectorConfig& config() const { return config_; }
  /// New knobs from the next frame on (a person tuning the search while it runs).
  void set_config(BlobDetectorConfig config);
  /// Flood fills started since the last call of this function (work done, for stats).
  int take_fill_count() { return std::exchange(fill_count_, 0); }
  /// Every region a search fills exactly and turns away is appended to `log` (not owned;
  /// nullptr, the default, logs nothing). A diagnosis, not for every frame: it costs a
  /// push per rejected region (a textured floor makes hundreds).
  void set_rejection_log(std::vector<RejectedRegion>* log) { rejections_ = log; }
  /// The local threshold the last search used at pixel (x, y) of its ROI (grey level; 0
  /// where its tile had too little contrast to hold a marker). For diagnosis and tests.
  std::uint8_t local_threshold(int x, int y) const { return threshold_at(x, y); }

 private:
  struct Fill;
  void prepare(const cv::Mat& grey);
  bool begin_search(const cv::Mat& grey, cv::Rect& roi, std::optional<double> fixed_threshold = std::nullopt);
  bool seed_near(const cv::Mat& grey, cv::Rect roi, cv::Point2d expected_px, Blob& blob);
  // Fills from the dark pixels of `seeds` (within roi) on the seed rows; each region may
  // extend over all of roi.
  std::vector<Blob> scan(const cv::Mat& grey, cv::Rect roi, cv::Rect seeds);
  bool try_seed(const cv::Mat& grey, cv::Rect roi, int x, int y, Blob& blob);
  void compute_thresholds(const cv::Mat& grey, cv::Rect roi);
  // The dark region through the seed, as row extents in row_min_x_/row_max_x_.
  // sweep_fill() follows each row's extent from its neighbours' (cheap; exact for a
  // marker's disc, but an enclosing shape's extents also take what it encloses); it
  // leaves the mask as it is, and false (with the extents reset) for a region cut by
  // the ROI or too large. flood_fill() is the exact run-by-run fill; it clears what it
  // takes from the mask and says false for a region cut by the ROI or too large.
  // try_seed() keeps a swept region only when it is a disc at least half dark with a
  // dark centre (as a marker's black hole); anything else is filled again exactly. So
  // only a thick dark ring (a hole under 0.7 of its diameter) with a marker inside whose
  // black lies on the ring's very centre hides that marker from a full-frame search.
  bool sweep_fill(cv::Rect roi, int seed_x, int seed_y, Fill& fill);
  bool flood_fill(cv::Rect roi, int seed_x, int seed_y, Fill& fill);
  // The region's ellipse from its sub-pixel chords, row by row and then column by column
  // (the columns' extents found only once its rows' ends leave the outline a chance).
  bool measure(const cv::Mat& grey, const Fill& fill, Blob& blob);
  // The cheap looks (area, compactness), then measure(); false for a region turned away.
  bool measure_region(const cv::Mat& grey, const Fill& fill, Blob& blob);
  void find_column_extents(const Fill& fill);   // col_min_y_/col_max_y_ from the row extents
  bool centre_is_dark(const Blob& blob) const;  // the mask at the blob's centre pixel
  void clear_swept_region(const Fill& fill);    // the mask within a sweep's row extents
  // Least area of a region that may be a marker's disc (config's smallest diameter,
  // foreshortened by max_axis_ratio, with a margin), pixels.
  double min_disc_area() const;
  // A cheap look at the region's bounding box and row extents before measure(): false
  // for a region far from any ellipse measure() would accept (long, thin or ragged).
  bool could_be_ellipse(const Fill& fill) const;
  void reset_region(const Fill& fill);  // row and column extents back to empty
  void clear_row_extents(int y0, int y1);
  std::uint8_t threshold_at(int x, int y) const { return tile_threshold_[tile_row_[y] * tiles_x_ + tile_col_[x]]; }

  BlobDetectorConfig config_;
  cv::Size size_;
  int tiles_x_ = 0, tiles_y_ = 0;
  std::vector<int> tile_col_, tile_row_;                                // pixel column/row -> tile column/row
  std::vector<std::uint8_t> tile_min_, tile_max_;                       // raw tile statistics
  std::vector<std::uint8_t> tile_threshold_;                            // 0 marks a tile without contrast
  std::vector<std::uint8_t> row_min_scratch_, row_max_scratch_;         // first pass of the 3x3 spread
  std::vector<std::uint8_t> tile_range_;                                // max - min over each tile's 3x3 neighbourhood
  std::vector<std::int16_t> contrast_tiles_;                            // per tile row: columns of tiles with contrast
  std::vector<int> contrast_tile_count_;                                // per tile row: how many are listed
  mutable std::vector<std::array<double, 3>> row_chords_, col_chords_;  // measure()'s scratch
  int fill_count_ = 0;
  std::vector<RejectedRegion>* rejections_ = nullptr;
  bool exact_fills_ = false;                                        // detect_inside(): no sweeps
  double inside_bright_outline_ = 0.9;                              // detect_inside()'s min_bright_outline
  mutable RegionRejection last_rejection_ = RegionRejection::kCut;  // why measure_region() last said no
  int floor_range_ = 0;  // the floor's local contrast found by the last large search, grey levels
  // Per pixel, nonzero while it is dark (below its threshold) and not yet filled in the
  // current search (bit 1; bit 2 when it is dark enough to seed a fill): the fill and the
  // seed scan test one byte, and a fill clears what it takes. Valid inside the current
  // search's ROI only; written per tile of contrast.
  cv::Mat dark_;                            // a view into dark_storage_, the image's size
  cv::Mat dark_storage_;                    // dark_ with zero bytes beside each row
  std::vector<std::uint8_t> dark_written_;  // per tile: its block of dark_ may hold nonzero bytes
  // `local_thresholds`: the tile thresholds come from this search's tile statistics
  // (not one fixed threshold), so those statistics may be consulted too.
  void build_dark_mask(const cv::Mat& grey, cv::Rect roi, bool local_thresholds);
  // Ask for pixels towards L2 ahead of the passes that read them (hints, no effect on
  // results): the rows the statistics sample in tile row `ty` (tile columns tx0..tx1),
  // and every row of the tiles with contrast listed for tile row `ty`.
  void prefetch_sampled_rows(const cv::Mat& grey, int ty, int tx0, int tx1) const;
  void prefetch_contrast_tiles(const cv::Mat& grey, int ty) const;
  // One row of tile `tx` of the mask, byte by byte (`tile_row_index`: the tile row's
  // first index in the tile arrays; `in` and `out`: the grey and mask rows).
  void mask_tile_row_bytes(const std::uint8_t* in, std::uint8_t* out, std::size_t tile_row_index, int tx,
                           bool local_thresholds) const;
  std::vector<int> row_min_x_, row_max_x_, col_min_y_, col_max_y_;
  std::vector<int> row_stamp_;  // sweep_fill()'s scratch: per row, the sweep that last changed it
  // flood_fill()'s stack: a seed with the span of the row it was found from.
  struct FillSeed {
    int x, y, parent_y, parent_x0, parent_x1;
  };
  std::vector<FillSeed> fill_stack_;
  std::vector<int> mask_tiles_;  // build_dark_mask()'s scratch: tiles with contrast in a tile row
  // build_dark_mask()'s scratch: per tile (or pair of neighbouring tiles) with contrast
  // in a tile row, where it starts and the grey limits (threshold - 1) of each half, as
  // sixteen bytes for one vector load (plain bytes: no SIMD type in this header, which
  // code built for another instruction set includes too).
  struct MaskStep {
    alignas(16) std::array<std::uint8_t, 16> limit, deep_limit;
    int x0;
    bool pair;
  };
  std::vector<MaskStep> mask_steps_;
};

}  // namespace rilbed::vision
