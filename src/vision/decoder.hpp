// Decodes a marker blob into an ID and a heading by circular cross-covariance (paper
// 001, eq. 4-6): the grey levels on circles in the coded annulus are compared with the
// ideal signal of every available ID at every lag; the best lag gives the heading.
#pragma once

#include <opencv2/core.hpp>

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "vision/blob_detector.hpp"
#include "vision/circle_sampler.hpp"
#include "vision/marker_family.hpp"

namespace rilbed::vision {

/// Knobs of the decoder.
struct DecoderConfig {
  /// Samples around the circle. More resolves narrower slices (kUCP with large k) at a
  /// linear cost; 120 gives 3 degrees per sample.
  int samples = 120;
  /// Circles sampled across the code annulus (1 to 3), averaged per angle. More averages
  /// out sensor noise and JPEG blocks at a linear cost in pixel reads (the sampling is
  /// most of a full-frame decode).
  int circles = 1;
  /// Least grey-level difference between the marker's white outer ring and its black
  /// ring. Lower accepts fainter markers and more clutter.
  double min_ring_contrast = 20.0;
  /// Least fraction of the white ring's samples that must be brighter than the
  /// midpoint between black and white. Rejects dark clutter without a white surround.
  double min_white_ring_fraction = 0.85;
  /// Least spread of the coded signal (10th to 90th percentile) as a fraction of the
  /// ring contrast. Rejects uniform discs and rings that carry no code.
  double min_code_contrast = 0.45;
  /// The levels a printed marker must show where its code says (levels_agree), each as a
  /// fraction of the ring contrast: the key slice at most this far below the white ring,
  /// (blur of a small marker darkens it a little; a dark blob on a textured floor that
  /// merely correlates with a code reads far darker)... The key is the widest white
  /// slice (6UCP: 85 degrees against the data slices' 55): blur that takes 0.3 of the
  /// contrast from the key's middle leaves a lone white data slice's middle below the
  /// midpoint (Gaussian blur across the circle: the key's middle keeps erf(85/55 x) where
  /// a data slice's keeps erf(x) = 0.5), so the data bits are no longer read reliably and
  /// the marker is declined. 0.35 allows for the levels' own noise; 0.6 let a blurred
  /// 19 px ID 8 read as ID 1, and letters and digits printed on the floor pass as ID 7 or 8.
  double max_key_shortfall = 0.35;
  /// ...its black slices at most this far above the black ring...
  double max_black_excess = 0.35;
  /// ...and its hole (the centre) at most this far above the black ring.
  double max_hole_excess = 0.7;
  /// How many of 64 reads around the white ring may fall below the midpoint between the
  /// rings (levels_agree). Anything lying across a marker (a cable, a hand) breaks the
  /// ring where it crosses, and what it covers of the code can read as another code; 0
  /// declines such a marker (a miss beats a wrong ID). A clean marker reads 0 even blurred.
  int max_dark_white_ring_reads = 0;
  /// Least correlation of the code read on the annulus's inner and on its outer circle
  /// (each on its own) with the code found (levels_agree). A printed marker's slices run
  /// radially, so both circles read the same code; a digit, a texture's blob or the like
  /// that happens to correlate on one circle reads something else on the other. Clean
  /// markers give 0.7 and more, blurred to the limit of reading.
  double min_radial_agreement = 0.6;
};

/// The angular signal sampled from one blob.
struct SampledSignal {
  bool usable = false;         ///< false when the contrast tests failed
  std::vector<double> values;  ///< mean grey level per angle, CCW from the sampling axis
  double ring_contrast = 0.0;  ///< white ring minus black ring, grey levels
  double black_level = 0.0;    ///< median grey level of the black ring
  double white_level = 0.0;    ///< median grey level of the white ring
};

/// The best match of a signal against one ID.
struct CodeMatch {
  int id = 0;
  double score = -1.0;  ///< circular cross-covariance at the best lag, [-1, 1]
  /// On screen, CCW from +u, [0, 360). Refined below the sampling step only for IDs
  /// within 0.1 of the best score (the only ones that can be assigned); others carry
  /// the whole-sample lag's heading.
  double heading_deg = 0.0;
  /// The same direction as an angle in the unit-circle frame of the blob's shape
  /// (radians, counter-clockwise on screen as the decoder's samples: the direction is
  /// shape · (cos a, -sin a)); what a tracker predicts the next frame's key from.
  double key_angle_rad = 0.0;
  /// The same ID's best score at a heading away from this one's peak (beyond its main
  /// lobe: more than three quarters of the family's narrowest slice): high when two
  /// key-slice positions explain the marker almost equally well. Set by match_all for
  /// families of up to 16 IDs; -1 otherwise.
  double rival_score = -1.0;
};

/// What a spot check of a tracked marker found (Decoder::spot_check).
struct SpotCheck {
  double heading_deg = 0.0;    ///< as CodeMatch::heading_deg
  double key_angle_rad = 0.0;  ///< as CodeMatch::key_angle_rad
};

/// Decoder for a fixed family and a fixed set of available IDs; precomputes their ideal
/// signals. Immutable after construction, so one decoder may serve several threads.
class Decoder {
 public:
  /// Throws std::invalid_argument for an ID outside the family.
  Decoder(const MarkerFamily& family, const std::vector<int>& ids, DecoderConfig config = {});

  /// Samples the coded annulus of `blob` in the 8-bit grey image.
  SampledSignal sample(const cv::Mat& grey, const Blob& blob) const;
  /// The same into `out`, reusing its storage (no allocation once it has grown): what a
  /// per-frame loop over many blobs uses.
  void sample(const cv::Mat& grey, const Blob& blob, SampledSignal& out) const;
  /// The cheap sampling a tracked marker's confirmation uses: one circle (the middle of
  /// the code annulus) instead of three, and the rings' levels given by the caller (read
  /// by the edge fit), so no ring is sampled. Of sample()'s contrast tests only the rings'
  /// contrast is made: the caller has tested the white ring, and confirms the one ID by
  /// its score, which a signal without the code's spread cannot reach.
  void sample_code(const cv::Mat& grey, const Blob& blob, double black_level, double white_level,
                   SampledSignal& out) const;

  /// Similarity of the signal to every available ID, in the order of ids() (the paper's
  /// Table 1 row for one object). Each entry carries the heading for that ID's best lag.
  /// The lag comes first from the key and guards every ID shares (correlated at every
  /// lag); each ID is then scored at the lags next to it.
  /// For more than 16 IDs the decoder first finds the heading from the slices all IDs
  /// share, reads the code bits there, and scores only that code and the codes with one
  /// ambiguous bit (a slice that reads near the midpoint) flipped, refined around the
  /// key's lag (they share the key, so their peaks lie there); the others get -1 (they
  /// cannot be the best match unless a clear bit misreads).
  std::vector<CodeMatch> match_all(const SampledSignal& signal, const Blob& blob) const;
  /// The same into `out` (replacing its contents, reusing its storage).
  void match_all(const SampledSignal& signal, const Blob& blob, std::vector<CodeMatch>& out) const;

  /// Whether the marker's grey levels are where `match` (its ID at its heading) says a
  /// printed marker has them, against the rings' levels in `signal` (sampled by sample()
  /// or sample_code()): the key slice white, the black slices and the hole black (see
  /// DecoderConfig::max_key_shortfall). Correlation alone is blind to levels: a dark blob
  /// on a textured floor can correlate with a code at 0.9 with its "white" key darker
  /// than the black ring. Reads one small circle (the hole) besides the signal.
  bool levels_agree(const cv::Mat& grey, const Blob& blob, const SampledSignal& signal, const CodeMatch& match) const;

  /// Whether the white ring around `blob` (the dark disc; centre and shape) is unbroken:
  /// at most DecoderConfig::max_dark_white_ring_reads of 64 reads around its middle lie
  /// at or below the midpoint of `black_level` and `white_level` (grey levels). Anything
  /// lying across the ring (a cable's end, a hand) breaks it, and a disc's outline fitted
  /// through it is pulled towards what lies there. Part of levels_agree; a tracked marker
  /// re-found by its outline is held to it too. 64 reads.
  bool white_ring_unbroken(const cv::Mat& grey, const Blob& blob, double black_level, double white_level) const;

  /// Similarity of the signal to one ID (which must be one of ids()): what a tracked
  /// marker needs to confirm its ID at a fraction of match_all's cost.
  /// With `expected_heading_deg` (the heading last seen, on screen) only lags within a
  /// 15 degrees of it are searched; if the best of them lies on the window's edge (the
  /// marker turned further), every lag is searched as without it.
  CodeMatch match_one(const SampledSignal& signal, const Blob& blob, int id,
                      std::optional<double> expected_heading_deg = std::nullopt) const;

  /// A tracked marker's heading from a few reads, without its whole signal: the key
  /// slice's bisector is where the grey levels just inside its two edges balance (found
  /// on two circles of the code annulus, near `expected_key_angle_rad`, the bisector
  /// predicted in the unit-circle frame of `blob`'s shape), and then every slice's middle
  /// is read and must have the ID's colour by a clear margin. About a quarter of
  /// sample_code() and match_one() together. `blob` is the marker's disc this frame;
  /// `black_level` and `white_level` the rings' grey levels (from the edge fit). Returns
  /// nothing when the marker turned by more than 9 to 15 degrees from the prediction
  /// (by its size), an edge is not where the balance puts it, or a slice does not read
  /// its colour: the caller then correlates the whole signal. It gives no similarity
  /// score. Throws std::invalid_argument for an ID not decoded here.
  std::optional<SpotCheck> spot_check(const cv::Mat& grey, const Blob& blob, int id, double expected_key_angle_rad,
                                      double black_level, double white_level) const;

  /// The on-screen heading `heading_deg` as an angle in the unit-circle frame of
  /// `blob`'s shape (see CodeMatch::key_angle_rad).
  double key_angle_of_heading(const Blob& blob, double heading_deg) const;

  const std::vector<int>& ids() const { return ids_; }
  const DecoderConfig& config() const { return config_; }

 private:
  // The ideal signal is piecewise constant, so its correlation with x at lag L is
  // sum over colour edges e of step(e) * P(e + L), where P is the running integral of the
  // mean-free signal (periodic, since the signal sums to zero). That costs one term per
  // edge instead of one per sample.
  struct Ideal {
    int id = 0;
    std::vector<double> edge;       // positions of colour changes, in samples, in [0, n)
    std::vector<double> step;       // normalised level before the edge minus level after it
    std::vector<int> edge_index;    // floor(edge + 0.5): the bin the edge falls in
    std::vector<double> edge_frac;  // edge + 0.5 - edge_index
    // Edges in the order their running-integral bin boundaries are met going up from a
    // whole lag (by decreasing edge_frac): what refine_peak walks through.
    std::vector<int> knot_order;
  };
  // The mean-free signal's running integral doubled (2n + 2 entries; with the signal
  // itself doubled beside it for a search over every lag), and its norm.
  struct Prepared {
    std::vector<double> doubled_cumulative, doubled_signal;
    double norm = 0.0;
    double mean = 0.0;
  };
  // Fills `p`'s running integral and norm (reusing its storage) from the signal.
  void prepare(const SampledSignal& signal, Prepared& p) const;
  // Adds the doubled signal that coarse_peak reads (a search over every lag).
  void prepare_doubled(const SampledSignal& signal, Prepared& p) const;
  // Lag (samples, on the sampling axis) at which the key's bisector points along the
  // on-screen heading for this blob's ellipse: heading_on_screen's inverse.
  double lag_of_heading(const Blob& blob, double heading_deg) const;
  // Best whole-sample lag of one ideal and its (unnormalised) correlation.
  std::pair<int, double> coarse_peak(const Prepared& p, const Ideal& ideal, std::vector<double>& scratch) const;
  // Best whole-sample lag within `reach` samples of `centre_lag` (the first of equal ones
  // from the low end).
  std::pair<int, double> local_peak(const Prepared& p, const Ideal& ideal, int centre_lag, int reach) const;
  // The lag refined below one sample, with its correlation.
  std::pair<double, double> refine_peak(const Prepared& p, const Ideal& ideal, int lag, double value) const;
  double correlate(const Prepared& p, const Ideal& ideal, double lag) const;
  // The correlation at every whole-sample lag into `out` (n entries), unnormalised.
  void correlate_all_lags(const Prepared& p, const Ideal& ideal, std::vector<double>& out) const;
  // The running integral at fractional sample t (any t; it is periodic).
  double integral_at(const Prepared& p, double t) const;
  double heading_on_screen(const Blob& blob, double lag) const;

  static constexpr int kRingSamples = 16;    // samples on each of the two rings (medians, a white-ring count)
  static constexpr int kExhaustiveIds = 16;  // above this many IDs, decode by key and bits
  // A code bit whose slice mean lies within this fraction of the key's contrast from
  // the midpoint is ambiguous: the code with that bit flipped is scored as well.
  static constexpr double kAmbiguousBit = 0.25;
  // A tracked marker turns at most this many degrees between frames before its
  // confirmation falls back to the search over every lag.
  static constexpr double kTrackReachDeg = 15.0;
  // A slice's middle must lie this fraction of the ring contrast beyond the midpoint
  // grey on its colour's side, and the key's edges within kSpotEdgeBand of it, in a
  // spot check. Generous (a clean marker reads its slices at about +-0.45 and its edges
  // near 0), so that only a wrong place, a wrong ID or a damaged marker fails.
  static constexpr double kSpotMargin = 0.2;
  static constexpr double kSpotEdgeBand = 0.3;
  // Per ID (in the order of ids_), its slices' middles relative to the key's bisector
  // as unit vectors (cos, sin of the angle counter-clockwise), padded with zeros to a
  // multiple of four for the four-wide sampler, and their colours as signs.
  struct SpotSlices {
    std::vector<float> cos, sin;
    std::vector<float> sign;  // +1 for a white slice, -1 for a black one
    int count = 0;
  };
  std::vector<SpotSlices> spot_slices_;
  double key_half_cos_ = 1.0, key_half_sin_ = 0.0;  // half the key slice's width, as a unit vector
  int track_reach_samples_ = 0;                     // kTrackReachDeg in samples, rounded up
  int rival_guard_samples_ = 0;  // CodeMatch::rival_score's main lobe: lags this close to a peak are its own
  // Entries of the running integral past 2n + 2 that local_peak reads for the windows the
  // decoder uses (at most one lag either side, scored as two pairs of lags); a wider
  // window falls back to correlate() per lag.
  static constexpr int kLocalWindowPad = 1;
  void build_key_template(const MarkerFamily& family);
  static void order_knots(Ideal& ideal);
  void match_by_key(const Prepared& p, const Blob& blob, std::vector<CodeMatch>& out) const;
  Ideal key_;                                            // key and guards only
  bool decode_by_bits_ = false;                          // more than kExhaustiveIds IDs: match_by_key
  std::vector<std::pair<double, double>> slice_bounds_;  // slices at lag 0, in samples; empty: exhaustive
  std::vector<int> index_of_id_;                         // ID -> index in ideals_, -1 if absent
  DecoderConfig config_;
  MarkerFamily family_;  // the slices' colours, for levels_agree
  CircleDirections sample_directions_, ring_directions_;
  CircleDirections dense_ring_directions_;  // levels_agree's 64 reads of the white ring
  std::vector<double> circle_radii_;        // as fractions of the marker's outer radius
  std::vector<int> ids_;
  std::vector<Ideal> ideals_;
};

}  // namespace rilbed::vision
