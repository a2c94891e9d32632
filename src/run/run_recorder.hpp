// Writes a run's folder: trajectories.csv (every robot at every control step),
// events.csv (collisions, behaviour changes, formation), summary.json and a picture of
// the trajectories (trajectories.svg). Rows are flushed as they come, so a run that is
// interrupted keeps everything recorded so far.
#pragma once

#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/geometry.hpp"
#include "core/time.hpp"

namespace rilbed::run {

/// One robot at one control step.
struct TrajectorySample {
  TimeUs t_us = 0;
  int id = 0;
  Pose2 pose;
  std::string_view behaviour;  ///< a static string
};

/// Something that happened during a run. `kind` is one of "collision",
/// "behaviour", "subteams", "formed", "broken", "health" (a real robot's link or
/// sighting changed), "note"; `id` and `other` are robot IDs (0: none,
/// negative: not a robot, e.g. -1 wall, -2 obstacle, -3 moving obstacle).
struct RunEvent {
  TimeUs t_us = 0;
  std::string kind;
  int id = 0;
  int other = 0;
  std::string detail;
};

/// A node of a tape network a robot reported: a `track_node` event (track_explore's).
struct ReportedTrackNode {
  int id = 0;        ///< the event's `other`
  std::string kind;  ///< "end", "corner", "tee", "cross"
  Vec2 position_m;   ///< field frame
  TimeUs t_us = 0;   ///< when it was reported
};

/// The node a `track_node` event reports; nullopt when its detail is not a JSON object
/// with `kind` (a string), `x_m` and `y_m` (numbers). Events may come from any program on
/// the bus: what does not parse is no node, never an exception.
std::optional<ReportedTrackNode> reported_track_node(const RunEvent& event);

/// What the SVG shows besides the trajectories (field frame, metres).
struct FieldDrawing {
  double width_m = 1.5;
  double height_m = 1.2;
  std::vector<std::vector<Vec2>> obstacles;                  ///< closed polygons
  std::vector<std::pair<std::vector<Vec2>, double>> tracks;  ///< polylines with their width
  std::vector<Vec2> beacons;
  /// Robots that are real (drawn apart from virtual ones, with a legend).
  std::set<int> real_robot_ids;
  /// Robots' bodies where the run described them: a disc's radius, or a convex outline in
  /// the robot's frame; a robot in neither is drawn as a Khepera (27.5 mm).
  std::map<int, double> body_radius_m;
  std::map<int, std::vector<Vec2>> body_outline_m;
};

/// Writes one run's folder. Not thread-safe. The picture shows each robot's path (solid
/// for a virtual robot, dashed for a real one), its start (a small circle) and its last
/// pose (a disc for a virtual robot, a square for a real one, with its heading), and a
/// legend below the field.
class RunRecorder {
 public:
  /// Creates `dir` (and parents) and opens the two CSV files with their headers. Throws
  /// std::runtime_error naming the path if it cannot.
  RunRecorder(const std::filesystem::path& dir, FieldDrawing field);
  /// Appends rows to trajectories.csv (header t_s,id,x_m,y_m,theta_deg,behaviour;
  /// theta in degrees CCW from +x, [0, 360)) and keeps every 5th sample per robot for the picture.
  void add_samples(const std::vector<TrajectorySample>& samples);
  /// Appends a row to events.csv (header t_s,kind,id,other,detail). The track explorers'
  /// `track_node` and `track_edge` events are also kept for track_map.json.
  void add_event(const RunEvent& event);
  /// Writes summary.json (the given object, pretty-printed), track_map.json when a robot
  /// reported track nodes or edges (that robot's map; the one with the most edges when
  /// several did) and trajectories.svg; flushes
  /// and closes the CSV files. Call once at the end.
  void finish(const nlohmann::json& summary);
  const std::filesystem::path& dir() const { return dir_; }
  /// Replaces the field the picture is drawn on (a run folder written from messages
  /// learns it from the run's world, which may come after the first rows).
  void set_field(FieldDrawing field) { field_ = std::move(field); }

 private:
  void write_svg() const;
  // A robot's map of the track network, from its track_node and track_edge events (the
  // latest of each ID).
  struct TrackMap {
    std::map<int, nlohmann::json> nodes, edges;
  };
  void keep_track_event(const RunEvent& e);
  void write_track_map() const;
  std::map<int, TrackMap> track_maps_;  // by robot
  std::filesystem::path dir_;
  FieldDrawing field_;
  std::ofstream trajectories_, events_;
  std::map<int, std::vector<Vec2>> paths_;  // per robot, thinned
  std::map<int, Pose2> last_pose_;
  std::map<int, int> sample_count_;
  int rows_since_flush_ = 0;
  bool finished_ = false;
};

/// Escapes a field for CSV (quotes it if it holds a comma, quote or newline).
std::string csv_field(std::string_view text);

}  // namespace rilbed::run
