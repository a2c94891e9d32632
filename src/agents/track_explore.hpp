// track_explore: paper 000's case study (§9) controller. From anywhere in the field it
// finds a tape, then visits every edge of the tape network knowing only its track sensor
// array, its proximity sensors and its wheel counters (not the map), and builds the
// network's graph as it goes.
//
// How: it follows the tape; a side arm or the loss of the tape says a node is near
// (read_track_array); it drives to where the node should be and turns once on the spot
// (BranchScan), which tells the node's kind, its ways and where it is. A node it has met
// before (within match_radius_m of where its odometry says it is) corrects the odometry:
// position to the node's, heading by the ways' directions, so that drift does not grow
// from node to node. Gentle corners that the follower takes without losing the tape are
// found from the path the sensor row drew (two straight stretches meeting at an angle).
// (The odometry corrections apply with correct_odometry only, off by default.)
// It then leaves by a way it has not taken, or drives the known graph to the nearest
// node that has one; when no way is left untaken it is done. Each node becomes a
// `track_node` event, each edge a `track_edge` event; the run folder's track_map.json is
// made from them.
#pragma once

#include <array>
#include <deque>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "agents/controller.hpp"
#include "agents/dead_reckoning.hpp"
#include "agents/steering.hpp"
#include "agents/track_features.hpp"

namespace rilbed::agents {

/// Knobs of the explorer.
struct TrackExploreConfig {
  double speed_mps = 0.1;          ///< along the tape, m/s
  double search_speed_mps = 0.12;  ///< while looking for a tape, m/s
  double scan_turn_radps = 1.5;    ///< turning on the spot at a node, rad/s (slower resolves ways better)
  double turn_radps = 2.5;         ///< turning to a way, rad/s
  /// Turn rate per metre of the tape's offset across the front, rad/s per m.
  double follow_gain = 90.0;
  double wheel_base_m = kWheelBase_m;  ///< for the odometry
  /// A node scanned within this of a known one is that node, metres. Above the odometry's
  /// drift between two nodes, below the closest two nodes.
  double match_radius_m = 0.07;
  /// Cues (arms, bends) are ignored this far after leaving a node: its other ways still
  /// pass under the array. Metres of travel.
  double leave_zone_m = 0.06;
  /// The tape is lost after this much travel with no element on it, metres.
  double lost_after_m = 0.006;
  /// A bend in the sensor row's path sharper than this is a corner node, degrees.
  double bend_min_deg = 27.0;
  /// A new node seen from off its centre is looked round again from where its ways seem to
  /// meet, at most this many times (each about 4 s).
  int max_rescans = 2;
  /// Correct the odometry from the map: at a node met again, on tape followed before, and
  /// spreading what a known node reveals over the nodes found since. Off by default: it
  /// does not yet make maps better under wheel slip (see bench/README.md), and with exact
  /// wheel counters it can only add error.
  bool correct_odometry = false;
  /// Give up (done, with what it has) after this much simulated time, seconds; 0: never.
  double time_limit_s = 0.0;
  TrackReadingConfig reading;
  BranchScanConfig scan;
  SteeringConfig steering;
};

/// The graph an explorer has built: nodes with their ways, edges between ways. A value.
struct ExploredTrackMap {
  static constexpr int kUntaken = -1;  ///< Way::edge of a way not yet driven
  static constexpr int kNoTape = -2;   ///< Way::edge of a way whose tape was not found from the node
  struct Way {
    double direction_rad = 0.0;  ///< leaving the node, map frame
    int edge = -1;               ///< the edge along it; kUntaken, or kNoTape when none was found there
    /// Whether direction_rad comes from following the tape (a line through 4 cm or more
    /// of it), not from the turn on the spot: only such a way corrects the heading.
    bool followed = false;
    Vec2 point_m;  ///< a point on the way's centre line, when followed
  };
  struct Node {
    int id = 0;
    TrackFeatureKind kind = TrackFeatureKind::kEnd;
    Vec2 position_m;
    std::vector<Way> ways;
    /// Whether a turn on the spot has read its ways from (within 8 mm of) its centre; if
    /// not, the robot turns there once more the first time it leaves it.
    bool looked_from_centre = false;
  };
  struct Edge {
    int from = 0, from_way = 0;
    int to = 0, to_way = 0;
    double length_m = 0.0;
  };
  std::vector<Node> nodes;
  std::vector<Edge> edges;

  /// The node within `radius_m` of `at` nearest to it, or -1.
  int nearest_node(Vec2 at, double radius_m) const;
  /// The way of `node` nearest `direction_rad`.
  int nearest_way(int node, double direction_rad) const;
  /// Whether some node has a way not yet taken.
  bool has_untaken_way() const;
  /// A route from `from` to the nearest node (by edge length) that has an untaken way:
  /// the ways to leave by, in order; empty when `from` has one itself or none is reachable.
  std::vector<std::pair<int, int>> route_to_untaken(int from) const;
  /// track_map.json's JSON: {"nodes": [{id, kind, x_m, y_m}], "edges": [{from, to, length_m}]}
  /// with the network's kind names (end, corner, tee, cross).
  std::string to_json() const;
};

/// The network's kind name ("end", "corner", "tee", "cross") of a feature.
std::string_view track_node_kind_of(TrackFeatureKind kind);

/// The explorer. Behaviours: "search", "acquire", "scan", "centre", "turn", "find", "follow",
/// "approach", "avoid", "done".
class TrackExploreController final : public Controller {
 public:
  /// `array`: the robot's track elements, in the order of its readings. Throws
  /// std::invalid_argument for an array with no element 8 mm or more off the robot's
  /// centre (a turn on the spot would see nothing).
  TrackExploreController(TrackArray array, TrackExploreConfig config = {});
  ControlOutput step(const ControlInput& input) override;
  bool done() const override { return mode_ == Mode::kDone; }
  bool reports_events() const override { return true; }
  void take_events(std::vector<ControllerEvent>& out) override;

  /// The graph so far.
  const ExploredTrackMap& map() const { return map_; }
  /// The pose its odometry believes, map frame.
  Pose2 believed_pose() const { return odometry_.pose(); }

 private:
  enum class Mode { kSearch, kAcquire, kScan, kCentre, kTurn, kFind, kFollow, kApproach, kDone };
  struct Leg {  // the edge being driven
    int from_node = -1, from_way = -1;
    double start_travel_m = 0.0;  // odometer reading when it left the node
  };
  // A stretch of tape the array followed, as a line (map frame).
  struct TapeLine {
    Vec2 point_m;
    double heading_rad = 0.0;  // the way the robot went along it
  };
  // What the robot found where it stopped: by a turn on the spot (its ways and their
  // points), or a bend of the path.
  struct Arrival {
    TrackFeatureKind kind = TrackFeatureKind::kEnd;
    Vec2 node_m;                   // where it thinks the node is (odometry)
    std::vector<double> ways_rad;  // the ways it saw
    std::vector<Vec2> way_points_m;
    std::optional<Vec2> scanned_from_m;   // where it turned (none for a bend)
    double heading_rad = 0.0;             // the heading it came in with
    std::optional<TapeLine> followed_in;  // the tape it followed in, when it followed enough
  };
  struct PathPoint {
    double travel_m;
    Vec2 sensor_m;  // where the tape's centre was under the array, map frame
  };

  // Where across the array the tape it follows should lie (TrackArrayReading::run_offset_m).
  double followed_tape_offset() const;
  ControlOutput search(const ControlInput& input, const TrackArrayReading& reading);
  ControlOutput follow(const TrackArrayReading& reading);
  ControlOutput acquire();
  ControlOutput centre();
  ControlOutput approach();
  ControlOutput turn(const TrackArrayReading& reading);
  ControlOutput find(const TrackArrayReading& reading);
  ControlOutput scan(const ControlInput& input);
  void start_scan();
  // Where a node is, from a turn off its centre: the other ways' crossings dropped onto the
  // tape it came in along.
  Vec2 node_from_in_line(const ScanResult& result) const;
  void after_scan(const ScanResult& result);
  // A node met (scanned, or a bend): matched or added, the leg closed as an edge, the
  // odometry corrected. Returns the node's id.
  int arrive(const Arrival& arrival, double length_m);
  // Where the known node is in the odometry's frame, from this arrival's crossings and the
  // node's followed ways (turned by `turn_rad`, the heading correction); the arrival's own
  // estimate when they do not place it.
  Vec2 locate_known(const ExploredTrackMap::Node& known, const Arrival& arrival, double turn_rad) const;
  // Records that a way was followed along `line`; a node with two such ways crossing is
  // moved to where they meet (and reported again).
  void set_followed(int node, int way, const TapeLine& line);
  // Corrects the odometry's heading and place across the tape on a tape the map knows.
  void hold_to_known_tapes(double travel_m);
  // Spreads the error a known node revealed over the nodes found since the last one.
  void spread_closure(Vec2 error_m);
  // Adds to a known node the ways a new turn on it saw that it lacks (`at`: the node in
  // the odometry's frame; `turn_rad`: the heading correction).
  void merge_ways(int node, const Arrival& arrival, Vec2 at, double turn_rad);
  void leave(int node);
  void leave_by(int node, int way);
  std::optional<PathPoint> bend_corner();
  // The tape the array followed between two odometer readings (a line through the path's
  // points), when it covers at least 4 cm.
  std::optional<TapeLine> fitted_line(double from_travel_m, double to_travel_m) const;
  // The tape just before the node the robot is arriving at, if it followed enough of it
  // since leaving the last one.
  std::optional<TapeLine> arrival_line() const;
  void emit_node(const ExploredTrackMap::Node& node);
  void emit_edge(int edge);
  ControlOutput drive(double speed_mps, double turn_radps, std::string_view behaviour) const;

  TrackArray array_;
  TrackExploreConfig config_;
  std::vector<int> sides_;
  int centre_element_ = -1;
  double sensor_ahead_m_ = 0.0;  // how far ahead of the centre the array reads
  DeadReckoning odometry_;
  BranchScan scanner_;
  ExploredTrackMap map_;
  std::vector<ControllerEvent> events_;
  bool anchored_ = false;
  Mode mode_ = Mode::kSearch;
  Leg leg_;
  bool on_leg_ = false;
  std::vector<std::pair<int, int>> route_;
  double target_heading_rad_ = 0.0;
  Vec2 acquire_at_m_;                // where the array first saw a tape
  bool search_turning_ = false;      // turning away from a wall while searching
  double search_heading_rad_ = 0.0;  // the heading it turns to
  int search_bounces_ = 0;
  Vec2 centre_at_m_;                   // the node it drives to before leaving it (or turning again)
  bool scan_after_centre_ = false;     // centring to turn on a new node again
  int rescans_ = 0;                    // turns again on the node being arrived at
  int verifying_node_ = -1;            // the node it turns on again, from its centre, before leaving it
  Vec2 scanner_start_m_;               // where the current turn on the spot began
  double arrival_length_m_ = 0.0;      // the leg's length when it first stopped at the node
  double approach_until_m_ = 0.0;      // odometer at which the approach stops
  double approach_heading_rad_ = 0.0;  // heading the approach holds (and the arrival's)
  double off_since_m_ = -1.0;          // odometer when the tape was last lost, -1 while on it
  double cue_travel_m_ = 0.0;          // odometer when the cue that stopped the following came
  bool arm_pending_ = false;           // a side arm seen; junction or corner not yet told
  double arm_heading_rad_ = 0.0;       // the heading when the arm was seen
  Vec2 arm_node_m_;                    // where the node would be for an arm square to the tape
  bool approach_started_ = false;      // the approach has taken its start
  double approach_left_m_ = 0.0;       // distance to go when the approach started (negative: behind)
  double approach_from_m_ = 0.0;       // the signed odometer then
  double last_offset_m_ = 0.0;         // where the followed tape lay across the array at the last step
  bool leg_way_fitted_ = false;        // the way it left by has had its line fitted
  bool leg_way_known_ = false;         // ... on an earlier leg (it corrects the odometry)
  bool seen_on_leg_ = false;
  double find_sweep_rad_ = 0.0;
  int find_round_ = 0;
  std::deque<PathPoint> path_;
  double last_bend_deg_ = 0.0;
  // Nodes found since it last stood on a known one, with the odometer then.
  struct ChainNode {
    int node;
    double travel_m;
  };
  std::vector<ChainNode> chain_;
  double chain_start_m_ = 0.0;
};

}  // namespace rilbed::agents
