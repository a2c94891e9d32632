// The overhead-camera pipeline of paper 001 §4.2 for one stream of frames: blob
// detection, circular cross-covariance decoding, object-to-ID assignment, and a tracker
// that searches near each marker's last position before any full-frame search.
#pragma once

#include <opencv2/core.hpp>

#include <cmath>
#include <optional>
#include <vector>

#include "core/geometry.hpp"
#include "vision/blob_detector.hpp"
#include "vision/decoder.hpp"
#include "vision/disc_edge_fit.hpp"
#include "vision/marker_family.hpp"
#include "vision/marker_template.hpp"
#include "vision/occluder.hpp"
#include "vision/ring_search.hpp"

namespace rilbed::vision {

/// One identified marker in one frame, in image coordinates (u right, v down, pixels,
/// the centre of the top-left pixel is (0, 0)).
struct MarkerDetection {
  int id = 0;
  double u = 0.0;
  double v = 0.0;
  /// Heading of the robot's forward direction (bisector of the key slice), degrees
  /// counter-clockwise on screen from +u, i.e. atan2(-dv, du), in [0, 360).
  double heading_deg = 0.0;
  /// Circular cross-covariance of the sampled signal with the ID's ideal signal, in
  /// [-1, 1]; 1 is a perfect match. For a spot-checked marker (see spot_checked) the
  /// one of its last correlation.
  double score = 0.0;
  /// Diameter of the marker's dark disc scaled to the marker's outer diameter, pixels
  /// (the geometric mean of the ellipse axes).
  double diameter_px = 0.0;
  /// True when this frame found it by the local search around its last position.
  bool tracked = false;
  /// Grey level midway between the marker's black and white rings in this frame.
  double threshold_grey = 0.0;
  /// Affine map from the unit circle to the outline of the marker's dark disc (see
  /// Blob::shape), pixels.
  cv::Matx22d disc_shape = cv::Matx22d::eye();
  /// The heading as an angle in the unit-circle frame of disc_shape, radians (see
  /// CodeMatch::key_angle_rad).
  double key_angle_rad = 0.0;
  /// True when this frame only spot-checked its code (each slice's colour, see
  /// TrackerConfig::full_confirm_interval_frames): `score` is then the one its last
  /// correlation gave, at most that many frames ago.
  bool spot_checked = false;
};

/// Knobs of the whole pipeline.
struct TrackerConfig {
  BlobDetectorConfig blobs;
  DecoderConfig decoder;
  /// The whole-marker check a blob passes before it takes an ID or a track confirms
  /// one from a fill (MarkerTemplates): after the decoder's tests, the last guard
  /// against letters and digits printed on the floor.
  MarkerTemplateConfig templates;
  /// A read marker with something lying across it (a band over its white ring that goes
  /// on across the floor beyond) is declined: what the band covers of the code may read
  /// as another code, and a miss beats a wrong ID. Costs 192 reads per named marker.
  OccluderConfig occluder;
  /// How a tracked marker is re-found from its outline before any fill. In the frames
  /// that only spot-check its code (see full_confirm_interval_frames) `quick_edge_fit`
  /// comes first: the centre and size only (2 rows and 2 columns, the shape kept from the
  /// last full fit; on the benchmark's 32 px markers the centre stays within about
  /// 0.03 px RMS of the truth, at about half the cost). `edge_fit`, the whole ellipse,
  /// follows when the quick fit fails or its residual exceeds `shape_refit_residual`
  /// (the shape changed), and fits every frame that correlates the code: the shape drifts
  /// as the marker crosses the field (lens, perspective), and the heading is read
  /// through it.
  DiscEdgeFitConfig quick_edge_fit = [] {
    DiscEdgeFitConfig c;
    c.lines = 2;
    c.keep_shape = true;
    return c;
  }();
  /// The whole ellipse's fit (see quick_edge_fit). It is also the first re-fit of a
  /// doubtful blob (BlobDetectorConfig::max_doubtful_chord_error).
  DiscEdgeFitConfig edge_fit;
  /// The second re-fit of a doubtful blob, when edge_fit's fails: the notched region of
  /// a small, heavily blurred marker may put its first guess a pixel or two off and its
  /// outline is soft, so this fit reaches further (0.4 of the radius), along more lines
  /// (8 rows and 8 columns), and accepts fewer crossings (0.7), a looser ellipse (0.07
  /// RMS) and a larger change of area (0.6). On the tuning seeds it kept about half of
  /// the 24-32 px markers the first re-fit dropped. What it keeps still faces every test
  /// of the decoder and the template; set min_edge_fraction above 1 to turn it off.
  DiscEdgeFitConfig doubtful_edge_fit = [] {
    DiscEdgeFitConfig c;
    c.lines = 8;
    c.reach = 0.4;
    c.min_edge_fraction = 0.7;
    c.max_residual = 0.07;
    c.max_area_change = 0.6;
    return c;
  }();
  /// A named marker's outline fitted once more from its disc, dropping the crossings that
  /// lie off the ellipse (DiscEdgeFitConfig::max_outliers): a light cable over the edge of
  /// its black ring leaves the fill short of the outline there, and the fill's moments
  /// put the centre off towards the far side (on the lab footage a 25 px marker's by a
  /// pixel, its heading read 14 degrees off). When the fit dropped crossings and its
  /// centre lies more than `rim_refit_min_shift_px` from the fill's, the marker is read
  /// again there (its own ID, at least min_assign_score) and reported from the fit. On
  /// the stress set's tuning seed 777 (full searches) it took the worst heading error of
  /// 24-32 px markers from 6.4 to 4.0 degrees, and the centre error of markers a cable
  /// covers by 10-15 % from 0.64 to 0.27 px RMS (worst 1.38 to 0.66 px); no recall
  /// changed. Costs an edge fit of 8 rows and 8 columns per named marker in full searches
  /// and fills (about 2 microseconds; 4 of each cost half as much and left the worst
  /// heading at 6.4 degrees); max_outliers 0 turns it off. A tracked marker re-found by
  /// its edges (edge_fit) drops no crossing: there it cost a 24-32 px marker on seed 777
  /// and changed little else; one whose edges fail that fit is filled and re-read here.
  DiscEdgeFitConfig rim_refit = [] {
    DiscEdgeFitConfig c;
    c.lines = 8;
    c.max_outliers = 8;
    return c;
  }();
  double rim_refit_min_shift_px = 0.25;
  /// When both re-fits of a doubtful blob fail, the blob may be one lobe of a small,
  /// blurred marker's disc (see ring_search.hpp): the circle whose rings contrast most
  /// around it is searched for and, when found, fitted with `doubtful_edge_fit` (its
  /// guesses lie within a pixel of the centre, but motion blur smears the outline past
  /// the strict fit), then decoded as any blob. A full search does this only while some
  /// listed ID is still missing once the other blobs are assigned; a tracked marker's own
  /// window, at once. On the tuning seeds it raised recall at 24-32 px by 0.7-2.8 %
  /// (full-frame). Costs about 6 microseconds per such blob (FrameStats::ring_searches;
  /// a textured floor makes about 20); off with `use_ring_search`.
  RingSearchConfig ring_search;
  bool use_ring_search = true;
  /// A marker on a robot whose top is dark and wider than the marker lies inside a
  /// larger dark disc (the top around its white ring) that the search takes for a
  /// blob, and whose inside it then no longer searches. So, while some listed ID is
  /// still missing after a full search, the inside of every blob that was decoded but
  /// named nothing is searched again on its own (FrameStats::nested_searches). Only
  /// blobs at least `nested_disc_ratio` times the least marker's disc are: smaller ones
  /// cannot hold a marker. Costs a small search (a few microseconds) per such blob, and
  /// only in frames that miss a marker; off with `search_inside_unread`.
  /// A tracked marker on such a top is searched for the same way within its window when
  /// the fill from its predicted centre finds no disc of its size there (it took in the
  /// top): one small search, where the track would otherwise be lost to a full search.
  bool search_inside_unread = true;
  double nested_disc_ratio = 1.1;
  /// ...and only blobs that enclose something bright: at least this many of 16 rays from
  /// the blob's centre cross a pixel above its threshold between 0.3 and 0.95 of its
  /// radius (rays_crossing_bright). A top holding a marker has the marker's white ring
  /// all round (16 rays; 9 where blur dims it), a dark floor speck or a solid disc
  /// little (0-3). On the lab footage's diagnosis seed 101 no marker was found inside a
  /// blob below 9 rays, and 10 % of its searches are left out; on the stress set's tuning
  /// seed 777 65 %, none of which found a marker. Costs 16 short rays per unread blob;
  /// lower searches more blobs for nothing, higher risks a marker whose white ring a
  /// cable or blur breaks. 0 searches inside every unread blob.
  int nested_min_bright_rays = 6;
  /// The inside search seeds its fills only within this fraction of the enclosing blob's
  /// half extents around its centre, where a robot carries its marker: its hole and black
  /// slices seed it there, and most of the top's rim further out is left unfilled (a third
  /// of the inside search's cost on the lab footage). A marker whose disc reaches no seed
  /// row inside that box is not found by this search. A blob is searched only when 6 of
  /// 16 rays from its centre cross something bright (nested_min_bright_rays); if that is
  /// the marker's white ring, the marker's centre lies within 1.2 of its outer radius R
  /// of the blob's centre, so its disc comes within 0.42 R of it: inside the box, whose
  /// half width (0.4 of the top's radius) is 0.42 R or more for any top of radius 1.05 R
  /// or more. Only a sliver of the disc may lie there when the marker is far off a top
  /// barely wider than itself. 1 seeds the whole box.
  double nested_seed_fraction = 0.4;
  /// The least bright share of a disc's outline in that search (BlobDetectorConfig::
  /// min_bright_outline elsewhere): between the black ring and a dark top the white ring is
  /// thin, and blur takes it below the local threshold in places. What passes still faces
  /// every test of the decoder (its white ring unbroken) and the template.
  double nested_min_bright_outline = 0.7;
  /// See quick_edge_fit; a fraction of the radius (DiscEdgeFit::residual). A clean disc
  /// whose shape is as kept fits within about 0.01; lower refits the shape more often.
  double shape_refit_residual = 0.02;
  /// Re-find tracked markers by the edge fit first (the fill remains the fallback).
  /// Off, every tracked marker costs a fill of its disc: several times slower.
  bool use_edge_fit = true;
  /// Samples around the circle when a tracked marker's code is correlated against its
  /// own ID (see full_confirm_interval_frames). Fewer than the full decode's
  /// (decoder.samples) since one ID is checked, not told apart from the family. The
  /// correlation's heading is used only when the spot check fails: on the recorded clips
  /// 60 samples give 0.8-0.9 degrees RMS, 120 the full decode's 0.5-0.7, the spot check
  /// 0.4-0.7.
  int confirm_samples = 60;
  /// A tracked marker found again by its outline is spot-checked every frame: its
  /// heading from the balance of its key slice's edges, every slice's colour checked
  /// (Decoder::spot_check), at about a quarter of the cost of correlating its code. Its
  /// whole code is correlated (a fresh score, and the whole outline refitted) at least
  /// every this many frames, and at once when a spot check fails. 1 correlates every
  /// frame. The tracks' turns are staggered by ID, so each frame correlates about the
  /// same number of markers. Larger costs less and keeps a score (and a shape) longer;
  /// the heading does not suffer (the spot check's is the more precise).
  int full_confirm_interval_frames = 16;
  /// Smallest similarity at which an object may take an ID. Lower finds markers in
  /// worse images but lets clutter through more often.
  double min_assign_score = 0.75;
  /// A blob is named only when its best match (an ID at one heading) beats every other
  /// explanation by this much: any other ID of the whole family at any heading, and the
  /// same ID at a heading beyond the peak's main lobe (CodeMatch::rival_score).
  /// Otherwise it is declined (FrameStats::declined): a miss beats a wrong ID. A blob
  /// only ever takes the ID its own code reads best; when that ID is not listed, none.
  /// Higher declines more markers in poor images; lower lets ambiguous codes through.
  double ambiguity_margin = 0.05;
  /// Local-search window half-size as a multiple of the marker's diameter, plus the
  /// distance it moved in the last frame. Larger tolerates faster robots, costs more.
  double search_window_diameters = 0.75;
  /// When some expected IDs are missing, a full-frame search runs at most every this
  /// many frames (1: every frame). Larger makes missing robots cheaper and found later.
  int full_search_interval_frames = 1;
  /// A track is dropped after this many frames without a detection.
  int max_missed_frames = 15;
  /// Bonus added to the similarity of an object lying inside the search window of the
  /// track of the same ID. Keeps IDs stable when two codes look alike in a poor frame.
  double track_bonus = 0.05;
  /// A tracked marker found again near its prediction keeps its ID after a check
  /// against that ID alone, as long as its similarity stays above min_assign_score and
  /// within this of the score it had when last seen; otherwise it is decoded against
  /// the whole family again. Larger saves decoding, smaller re-checks more often.
  double confirm_drop = 0.08;
};

/// What became of one candidate blob in a search (MarkerTracker::set_verdict_log).
enum class CandidateFate {
  kRefitFailed,  ///< a doubtful blob whose outline fitted no clean ellipse (nor its rings, when searched)
  kLowScore,     ///< its best reading scored below min_assign_score
  kAmbiguous,    ///< another reading came within ambiguity_margin (FrameStats::declined)
  kLevels,       ///< its black and white levels are not a printed marker's (Decoder::levels_agree)
  kTemplate,     ///< the whole marker its reading names does not match (MarkerTemplates)
  kOccluded,     ///< something lies across it (a band over its white ring and the floor beyond: find_band_across)
  kNotChosen,    ///< its reading was a listed ID another blob took, or is not listed
  kNamed,        ///< it took an ID
};

/// The name of a fate ("refit failed", "low score", ...).
const char* fate_name(CandidateFate fate);

/// One candidate blob and what became of it.
struct CandidateVerdict {
  double u = 0, v = 0;     ///< its centre, pixels
  double diameter_px = 0;  ///< its dark disc's equivalent diameter
  CandidateFate fate = CandidateFate::kNamed;
  int id = 0;            ///< the ID its code reads best (0 before decoding)
  double score = 0;      ///< that reading's score
  double runner_up = 0;  ///< the next explanation's score
};

/// Per-frame work counters, for summaries and benchmarks.
struct FrameStats {
  bool full_search = false;  ///< a full-frame search ran
  int blobs = 0;             ///< candidate blobs that passed the shape tests
  int decoded = 0;           ///< blobs whose signal was decodable
  int fills = 0;             ///< dark regions filled (the detector's main work)
  int edge_fits = 0;         ///< tracked markers confirmed from their outline, without a fill
  int refits = 0;            ///< doubtful blobs (Blob::doubtful) whose outline was fitted again
  int refits_kept = 0;       ///< ...and that fitted a clean ellipse, so went on to decoding
  int ring_searches = 0;     ///< refits that failed and searched for the disc's rings (TrackerConfig::ring_search)
  int declined = 0;  ///< decoded blobs left unnamed: two explanations too close (TrackerConfig::ambiguity_margin)
  int nested_searches = 0;  ///< unread blobs searched inside (TrackerConfig::search_inside_unread)
  int occluded = 0;         ///< read markers declined for a band lying across them (TrackerConfig::occluder)
};

/// Runs the pipeline over a stream of frames of one size. Not thread-safe; one per
/// camera. The family is copied.
class MarkerTracker {
 public:
  /// `ids` are the IDs that may appear (paper: the "available markers"); each is given
  /// to at most one object per frame. Throws std::invalid_argument for an ID outside
  /// the family or an empty list.
  MarkerTracker(MarkerFamily family, std::vector<int> ids, TrackerConfig config = {});

  /// Processes one frame (8-bit grey or BGR). Returns the identified markers sorted by ID.
  std::vector<MarkerDetection> process(const cv::Mat& frame);

  /// Processes one frame with a full-frame search only, ignoring and not updating the
  /// tracks (what a single image gets).
  std::vector<MarkerDetection> detect_full_frame(const cv::Mat& frame);

  /// Forgets every track (e.g. after a cut in the footage).
  void reset();

  /// Counters of the last processed frame.
  const FrameStats& last_stats() const { return stats_; }
  /// Every candidate blob of the following searches and its fate is appended to
  /// `verdicts`, every dark region the blob detector turned away to `rejections` (neither
  /// owned; nullptr, the default, logs nothing). For finding out why a marker is missed
  /// (bench_stress --explain); a push per candidate, not for every frame of a run.
  void set_verdict_log(std::vector<CandidateVerdict>* verdicts, std::vector<RejectedRegion>* rejections = nullptr) {
    verdicts_ = verdicts;
    detector_.set_rejection_log(rejections);
  }
  /// The IDs this tracker assigns.
  const std::vector<int>& ids() const { return ids_; }
  const TrackerConfig& config() const { return config_; }
  /// New knobs from the next frame on (a person tuning the pipeline while it runs). The
  /// tracks are forgotten, so that the next frame finds every marker afresh under the new
  /// knobs (a tracked marker is only spot-checked, not held to the size limits and the
  /// least score again); that frame costs a full search. Rebuilds the decoders (a
  /// fraction of a millisecond).
  void set_config(const TrackerConfig& config);

 private:
  struct Track {
    int id = 0;
    double u = 0, v = 0, du = 0, dv = 0;  // position and per-frame motion
    double diameter_px = 0;
    double threshold_grey = 0;
    double score = 0;
    double heading_deg = 0;                  // on screen, as last seen
    cv::Matx22d shape = cv::Matx22d::eye();  // the disc's outline, as last seen
    int missed = 0;
    /// Frames since its code was last correlated (not only spot-checked).
    int frames_since_correlated = 0;
    /// Its turn per frame, degrees counter-clockwise on screen.
    double turn_deg = 0;
    /// Its heading in the coming frame (constant turn, coasting over misses), degrees in
    /// [0, 360).
    double predicted_heading_deg() const { return wrap_deg_360(heading_deg + turn_deg * (missed + 1.0)); }
    /// The heading last seen in the unit-circle frame of `shape` and its turn per frame
    /// there, radians: the spot check's prediction (its fit keeps the shape).
    double key_angle_rad = 0;
    double key_turn_rad = 0;
    double predicted_key_angle_rad() const { return key_angle_rad + key_turn_rad * (missed + 1.0); }
    /// Where it should be in the coming frame (constant motion, coasting over misses).
    cv::Point2d predicted() const { return {u + du * (missed + 1.0), v + dv * (missed + 1.0)}; }
    /// How far it moves by then, pixels.
    double predicted_travel() const { return (missed + 1.0) * std::hypot(du, dv); }
    /// Its disc where it should be in the coming frame, as last seen otherwise.
    Blob predicted_disc() const;
  };
  std::vector<MarkerDetection> assign(const cv::Mat& grey, const std::vector<Blob>& blobs, bool use_tracks,
                                      const std::vector<int>& taken_ids = {});
  std::optional<MarkerDetection> confirm(const cv::Mat& grey, const Track& track, const Blob& blob);
  // The tracked marker re-found by the edge fit around its prediction, confirmed.
  std::optional<MarkerDetection> confirm_by_edges(const cv::Mat& grey, const Track& track);
  // The disc and reading of a named marker whose rim something covers in part, re-read
  // from the outline fitted without the covered crossings (TrackerConfig::rim_refit);
  // nothing when its fill's disc stands.
  std::optional<std::pair<Blob, CodeMatch>> reread_covered_rim(const cv::Mat& grey, const Blob& blob,
                                                               const CodeMatch& match, double threshold_grey);
  // The blobs of a track's window when the fill from its prediction found none of the
  // track's size (a marker on a dark top): the window searched with exact fills, and of
  // what it holds the discs within a third of the track's size.
  std::vector<Blob> search_window_inside(const cv::Mat& grey, const Track& track, cv::Rect window);
  // The blob detector's full search, with its doubtful blobs settled (settle_doubtful;
  // those that fail go to `fragments`).
  std::vector<Blob> find_blobs(const cv::Mat& grey, std::vector<Blob>* fragments);
  // Replaces each doubtful blob by the ellipse fitted to its outline, or drops it. A blob
  // whose outline does not fit may be a lobe of a small blurred marker's disc: with
  // `fragments`, it is moved there (for rescue_fragments, should a listed ID be missing
  // once the rest are assigned); without, its disc is searched for at once.
  void settle_doubtful(const cv::Mat& grey, std::vector<Blob>& blobs, std::vector<Blob>* fragments = nullptr);
  // The disc found around a fragment (search_ring) and fitted from there, or nothing.
  std::optional<Blob> rescue_fragment(const cv::Mat& grey, const Blob& fragment);
  // While some listed ID is missing from `found`: the discs rescued from `fragments`
  // not at a found marker's place, assigned to the IDs still free, added to `found`.
  void assign_rescued(const cv::Mat& grey, const std::vector<Blob>& fragments, bool use_tracks,
                      std::vector<MarkerDetection>& found);
  cv::Mat to_grey(const cv::Mat& frame);
  // While some listed ID is missing from `found`: the blobs inside the decoded blobs that
  // named nothing (unread_), assigned to the IDs still free, added to `found`.
  void assign_nested(const cv::Mat& grey, bool use_tracks, std::vector<MarkerDetection>& found);
  // decoder_index_ for decoder_.
  void index_decoder();

  MarkerFamily family_;
  std::vector<int> ids_;
  std::vector<int> decoder_index_;  // for each of ids_, its column in the decoder's matches
  // assign()'s buffers, kept between frames: blobs x ids_ similarities (row-major), each
  // blob's matches from the decoder, each blob's black/white midpoint.
  std::vector<double> similarity_;
  std::vector<std::vector<CodeMatch>> matches_;
  std::vector<double> thresholds_;
  std::vector<bool> passed_;    // per blob: it passed every test before the assignment
  std::uint8_t load_sink_ = 0;  // keeps load_disc_area()'s loads (its value is never used)
  TrackerConfig config_;
  BlobDetector detector_;
  Decoder decoder_;
  Decoder confirm_decoder_;    // the listed IDs only, at confirm_samples: the edge-fit confirmation
  MarkerTemplates templates_;  // the listed IDs
  std::vector<Track> tracks_;
  std::vector<int> track_of_id_;    // per ID, its index in tracks_ or -1 (rebuilt per frame)
  std::vector<int> confirmed_ids_;  // process()'s, kept between frames (no allocation per frame)
  std::vector<Blob> fragments_;     // a full search's doubtful blobs whose outline did not fit (settle_doubtful)
  std::vector<Blob> unread_;        // a search's blobs decoded but named nothing (assign_nested)
  FrameStats stats_;
  int frames_since_full_ = 0;
  cv::Mat grey_buffer_;
  SampledSignal signal_;                               // reused for every blob: no allocation per blob
  SampledSignal reread_signal_;                        // reread_covered_rim's, beside signal_
  std::vector<Blob> named_discs_;                      // assign()'s blobs, as re-read
  std::vector<CandidateVerdict>* verdicts_ = nullptr;  // set_verdict_log's
  void log_verdict(const Blob& blob, CandidateFate fate, const CodeMatch* match = nullptr, double runner_up = 0);
};

/// Convenience: one full-frame detection of `ids` in one image with default knobs.
std::vector<MarkerDetection> detect_markers(const cv::Mat& image, const MarkerFamily& family,
                                            const std::vector<int>& ids, const TrackerConfig& config = {});

}  // namespace rilbed::vision
