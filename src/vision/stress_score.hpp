// Scores detections on the vision stress set (stress_scene.hpp): what became of every
// marker (found, where, which way) and every detection that is not a marker's own (a wrong
// ID, a false detection on the floor or its clutter, a heading far off), with summaries by
// marker size, blur, occlusion and ID. bench/bench_stress prints them; the stress CTest
// holds them to the stress set's targets (README of bench/).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "vision/marker_tracker.hpp"
#include "vision/stress_scene.hpp"

namespace rilbed::vision {

/// A reported heading further than this from the truth is a wrong detection, not an
/// inaccurate one, degrees.
inline constexpr double kStressWrongHeadingDeg = 10.0;

/// What became of one marker in one frame.
struct StressOutcome {
  int scene = 0, frame = 0, id = 0;
  double diameter_px = 0;  ///< StressTruth::diameter_px
  double occluded = 0;     ///< fraction of the disc covered
  double blur_px = 0;      ///< the frame's blur as one Gaussian's sigma: sqrt(sigma^2 + smear^2 / 12)
  bool touching = false;
  StressFloor floor = StressFloor::kPlain;
  bool found = false;            ///< its ID reported within half its diameter, heading within kStressWrongHeadingDeg
  double centre_error_px = 0;    ///< found: distance of the reported centre from the truth
  double heading_error_deg = 0;  ///< found: reported minus true, (-180, 180]
};

/// A detection that is not a marker's own.
struct StressMistake {
  enum class Kind {
    kWrongId,         ///< on a marker (within half its diameter) that has another ID
    kFalseDetection,  ///< on no marker: the floor or its clutter
    kWrongHeading,    ///< the right ID, but the heading more than kStressWrongHeadingDeg off
    kDuplicate,       ///< a second report of an ID already found on that marker
  };
  Kind kind = Kind::kWrongId;
  int scene = 0, frame = 0;
  int id = 0;                    ///< the ID reported
  int true_id = 0;               ///< the ID of the marker it lies on, 0 for none
  double u = 0, v = 0;           ///< where it was reported, pixels
  double heading_error_deg = 0;  ///< WrongHeading: reported minus true
};

/// Outcomes and mistakes, accumulated frame by frame.
class StressTally {
 public:
  /// Scores one frame of `scene`: `found` is what the detector reported for it, and
  /// `declined` how many markers it saw but declined to name (ambiguous).
  void add(const StressScene& scene, int frame, const std::vector<MarkerDetection>& found, int declined = 0);

  const std::vector<StressOutcome>& outcomes() const { return outcomes_; }
  const std::vector<StressMistake>& mistakes() const { return mistakes_; }
  int frames() const { return frames_; }
  int declined() const { return declined_; }
  /// Mistakes of one kind.
  int count(StressMistake::Kind kind) const;

 private:
  std::vector<StressOutcome> outcomes_;
  std::vector<StressMistake> mistakes_;
  int frames_ = 0;
  int declined_ = 0;
};

/// A summary of the outcomes that pass a filter.
struct StressStats {
  int markers = 0;
  int found = 0;
  double recall() const { return markers ? static_cast<double>(found) / markers : 0.0; }
  double centre_rms_px = 0, centre_max_px = 0;
  double heading_rms_deg = 0, heading_max_deg = 0;  ///< max: largest |error| among those found
  /// The ID whose mean heading error (reported minus true, over its found markers) is the
  /// largest in size, and that mean, degrees: a bias by code.
  int worst_bias_id = 0;
  double worst_bias_deg = 0;
};

/// Summarises the outcomes for which `keep` is true.
StressStats summarise(const std::vector<StressOutcome>& outcomes,
                      const std::function<bool(const StressOutcome&)>& keep);

/// Every mistake of a tally, one line each (scene, frame, kind, where), for a failing test's message.
std::string list_mistakes(const StressTally& tally);

/// The kind's name ("wrong ID", "false detection", ...).
const char* mistake_name(StressMistake::Kind kind);

}  // namespace rilbed::vision
