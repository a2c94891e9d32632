// Scores detections against ground truth: the CSV files `rilbed detect` writes and
// `rilbed synth` (or a lab's own labelling) provides. Used by `rilbed score`, the
// end-to-end tests and the demo.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace rilbed::vision {

/// One row of a detection or ground-truth CSV (columns found by header name).
struct MarkerRow {
  int frame = 0;
  int id = 0;
  double u = 0.0, v = 0.0, heading_deg = 0.0;
  std::optional<double> x_m, y_m, theta_deg;  ///< present when the file has the columns
};

/// Rows of a CSV file, or an error naming the file and line.
struct MarkerRowsResult {
  std::vector<MarkerRow> rows;
  std::string error;
  bool ok() const { return error.empty(); }
};

/// Reads a CSV with at least the columns frame,id,u,v,heading_deg (any order, extra
/// columns ignored; x_m,y_m,theta_deg read when present).
MarkerRowsResult read_marker_csv(const std::string& path);

/// How detections compare with the truth.
struct DetectionScore {
  int truth_markers = 0;  ///< (frame, id) pairs in the truth
  int found = 0;          ///< detected with the right ID within the match radius
  int wrong_id = 0;       ///< detections of an ID that is not within the radius of its truth
  int duplicates = 0;     ///< the same (frame, id) reported more than once
  double centre_rms_px = 0.0, centre_max_px = 0.0;
  double heading_rms_deg = 0.0, heading_max_deg = 0.0;
  int field_pairs = 0;  ///< found markers with field coordinates on both sides
  double field_rms_mm = 0.0, field_max_mm = 0.0;
  double theta_rms_deg = 0.0;
  double recall() const { return truth_markers ? static_cast<double>(found) / truth_markers : 0.0; }
};

/// Matches detections to truth by (frame, id); a detection counts as found when it lies
/// within `match_radius_px` of its truth, otherwise as a wrong ID.
DetectionScore score_detections(const std::vector<MarkerRow>& truth, const std::vector<MarkerRow>& detections,
                                double match_radius_px = 5.0);

/// A few lines for humans.
std::string format_score(const DetectionScore& score);

}  // namespace rilbed::vision
