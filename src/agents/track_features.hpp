// What a robot can know on board about a network of floor tape (paper 000 §8-9), from
// its track sensor array and its wheel counters alone: whether it is on the tape, where
// across its front the tape lies, whether a side arm or the loss of the tape says a node
// is near (TrackArrayReading, read_track_array), and, from one turn on the spot at that
// node (BranchScan), which ways the tape leaves it: an end, a corner (left or right), a
// T junction or a crossing, and where the node is.
//
// Why a turn on the spot: a row of three or five elements 10-15 mm apart sees a side arm
// only for the few millimetres it takes to cross it, and on tape nearly as wide as the row
// the outer elements flicker on while the robot merely drifts, so passing over a node
// cannot tell a 45-degree branch from drift. Turned once round the node's centre, each
// element sweeps a circle of its distance from the robot's centre and crosses every tape
// leaving the node; the middle of each crossing is a point on that tape's centre line, and
// the lines through those points meet at the node. A false alarm (drift on a straight
// tape) shows two opposite ways and is no node.
#pragma once

#include <span>
#include <string_view>
#include <vector>

#include "core/geometry.hpp"
#include "environment/track_sensor.hpp"

namespace rilbed::agents {

/// Where a robot's track sensor elements look, as a controller needs to know them.
struct TrackArray {
  /// Each element's footprint centre on the floor, robot frame (x forward, y left),
  /// metres, in the order of SensorReadings::track.
  std::vector<Vec2> points_m;
  /// The largest footprint's half extent, metres: how far from its centre an element
  /// can see tape.
  double footprint_radius_m = 0.0;

  /// From the robot's configured elements (their mounts and cones).
  static TrackArray of(std::span<const environment::TrackSensorConfig> elements);
  /// The element nearest the robot's forward axis (smallest |y|, then nearest x); -1
  /// for no elements.
  int centre_element() const;
};

/// Knobs of reading the array.
struct TrackReadingConfig {
  int max_value = 255;         ///< the elements' full scale
  double on_fraction = 0.5;    ///< an element sees tape at or above this share of max_value
  double tape_width_m = 0.02;  ///< the tape the lab lays: decides which elements can see a side arm
  /// An element can report a side arm when it sits at least this far beyond the tape's
  /// edge (its footprint included) while the tape is centred: nearer elements see the
  /// tape itself whenever the robot drifts. Metres.
  double arm_clearance_m = 0.003;
};

/// One reading of the array, as a controller uses it.
struct TrackArrayReading {
  bool on_track = false;  ///< at least one element sees tape
  int elements_on = 0;    ///< how many see it
  /// Where the tape lies across the robot's front: the mean lateral position of the
  /// elements that see it, metres, left positive; 0 when off the track.
  double offset_m = 0.0;
  /// The same for the run of neighbouring elements that see tape nearest `near_m` (the
  /// tape being followed, where other tapes also pass under the array); 0 when off.
  double run_offset_m = 0.0;
  bool arm_left = false;   ///< an element far enough left sees tape joined to the middle
  bool arm_right = false;  ///< the same on the right
};

/// Which elements can see a side arm (see TrackReadingConfig::arm_clearance_m): +1 left,
/// -1 right, 0 neither, per element.
std::vector<int> arm_sides(const TrackArray& array, const TrackReadingConfig& config);

/// Reads one set of track values (one per element of `array`). `sides` is arm_sides()'s
/// answer for the same array and config; `near_m` is where the tape being followed lay
/// (run_offset_m).
TrackArrayReading read_track_array(const TrackArray& array, std::span<const int> track,
                                   const TrackReadingConfig& config, std::span<const int> sides, double near_m = 0.0);

/// What a node is, as seen from the way the robot came in (paper 000 §9's features).
enum class TrackFeatureKind {
  kNone,         ///< two ways nearly opposite: a plain stretch of tape
  kEnd,          ///< one way: the tape stops
  kCornerLeft,   ///< two ways, the other turning left of the way in
  kCornerRight,  ///< two ways, turning right
  kTee,          ///< three ways
  kCross,        ///< four or more
};

/// "none", "end", "corner_left", "corner_right", "tee", "cross".
std::string_view track_feature_name(TrackFeatureKind kind);

/// Knobs of the turn on the spot.
struct BranchScanConfig {
  /// Two ways closer than this (degrees) are one: tapes leaving a node at a sharper angle
  /// than this are seen as one. Costs nothing; too large merges real branches.
  double merge_deg = 25.0;
  /// Two ways are a straight line (no corner) when they are within this of opposite,
  /// degrees: a tape turning by less than this is no corner (TrackNetwork's corner angle).
  double straight_deg = 30.0;
  /// Elements at least this share of the farthest element's distance from the robot's
  /// centre tell the ways apart (a 20 mm tape covers 60 degrees of a 20 mm circle, 38 of
  /// a 31 mm one); nearer ones give each way a second point, hence its direction and the
  /// node's place, when they are at least 6 mm nearer. 0..1.
  double min_radius_share = 0.8;
};

/// What a turn on the spot found.
struct ScanResult {
  /// Directions of the ways leaving the node, odometry frame, radians in (-pi, pi],
  /// counter-clockwise order from the first.
  std::vector<double> ways_rad;
  /// Per way, a point on its centre line (where the outer elements crossed it), odometry
  /// frame: with the way's true direction, it places the node when the robot did not
  /// turn on it (meet_of_lines).
  std::vector<Vec2> way_points_m;
  /// Where the ways' centre lines meet (the node), odometry frame, when two ways' directions
  /// are known from two radii each; else (and for an end) the scan's centre.
  Vec2 node_m;
  TrackFeatureKind kind = TrackFeatureKind::kNone;
  /// Index in ways_rad of the way the robot came in by (nearest the reverse of the
  /// heading it arrived with), -1 when there are none.
  int way_in = -1;
};

/// Collects the array's readings while the robot turns once on the spot, then finds the
/// ways the tape leaves from there. A value; one scan at a time.
class BranchScan {
 public:
  BranchScan(TrackArray array, TrackReadingConfig reading, BranchScanConfig config = {});

  /// Starts a scan with the robot at `pose` (odometry frame), having arrived heading
  /// `arrival_heading_rad` (the direction it travelled in; the way in is its reverse).
  void start(Pose2 pose, double arrival_heading_rad);
  /// Adds one reading taken at `pose` while turning (either way, on the spot).
  void add(Pose2 pose, std::span<const int> track);
  /// How far the robot has turned since start(), radians (absolute).
  double turned_rad() const { return turned_rad_; }
  /// Whether it has turned a full turn.
  bool complete() const;
  /// The ways and the node, from what was added.
  ScanResult result() const;

 private:
  struct Sample {
    double angle_rad;  // absolute direction of the element from the robot's centre
    Vec2 centre_m;     // the robot's centre then
    bool on;
  };
  TrackArray array_;
  TrackReadingConfig reading_;
  BranchScanConfig config_;
  // One way the tape leaves by: the mean of the outer elements' crossings and, when
  // nearer elements crossed it too, the mean of theirs.
  struct Way {
    Vec2 outer_m;
    double outer_radius_m = 0.0;
    Vec2 inner_m;
    double inner_radius_m = 0.0;
    int inner_count = 0;
  };
  std::vector<Way> crossings_to_ways() const;

  double farthest_m_ = 0.0;                   // the farthest element from the robot's centre
  std::vector<int> used_;                     // elements off the axis of the turn
  std::vector<bool> primary_;                 // per used element: far enough out to tell ways apart
  std::vector<std::vector<Sample>> samples_;  // per used element
  Pose2 start_;
  double last_heading_rad_ = 0.0;
  double turned_rad_ = 0.0;
  double arrival_heading_rad_ = 0.0;
};

/// The kind of a node with `ways` (directions, radians), entered heading
/// `arrival_heading_rad`; also says which way is the way in.
TrackFeatureKind classify_ways(std::span<const double> ways_rad, double arrival_heading_rad,
                               const BranchScanConfig& config, int* way_in = nullptr);

/// The point nearest the lines through `points_m[k]` along `directions_rad[k]` (least
/// squares; `fallback` when they are nearly parallel or fewer than two): where a node is,
/// from a point on each of its ways and their directions.
Vec2 meet_of_lines(std::span<const Vec2> points_m, std::span<const double> directions_rad, Vec2 fallback);

}  // namespace rilbed::agents
