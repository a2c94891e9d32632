// The parts of the world that never move (paper 000 §5.1, §6.1): the field and its
// boundary walls, static obstacles, reflective floor tracks and IR beacons (active
// targets, §6.10). Field frame: x right, y up, metres, origin at the field's lower-left
// corner; angles radians counter-clockwise from +x.
#pragma once

#include <array>
#include <span>
#include <string>
#include <vector>

#include "core/geometry.hpp"
#include "environment/shapes.hpp"

namespace rilbed::environment {

/// The rectangular field robots drive on.
struct FieldConfig {
  double width_m = 1.5;        ///< extent along x; the lab's field is 1.5 x 1.2 m
  double height_m = 1.2;       ///< extent along y
  bool boundary_walls = true;  ///< walls along the four edges; without them robots may leave
};

/// A static obstacle: a closed polygon, convex or not (not self-intersecting). The last
/// vertex connects back to the first; repeating the first vertex at the end is allowed.
struct ObstacleConfig {
  std::vector<Vec2> vertices_m;  ///< field frame, at least three
  std::string name;              ///< optional; error messages use it beside the index
};

/// A reflective track on the floor (paper 000 §8): a polyline of the given width that the
/// track sensor sees. Tracks are not obstacles; robots drive over them.
struct TrackConfig {
  std::vector<Vec2> points_m;  ///< at least two points
  double width_m = 0.02;       ///< full width of the tape
  bool closed = false;         ///< true: the last point joins the first (a loop)
  std::string name;            ///< optional, for error messages
};

/// An IR beacon (active target, paper 000 §6.10): a robot sees its ID and bearing when
/// it is within range_m of the beacon, inside its aperture, and no obstacle blocks the
/// line between them.
struct BeaconConfig {
  int id = 0;                       ///< what the direction finder reports; unique per map
  Vec2 position_m;                  ///< field frame
  double facing_rad = 0.0;          ///< direction of the aperture's middle
  double aperture_rad = 2.0 * kPi;  ///< full opening angle, (0, 2 pi]; 2 pi shines all round
  double range_m = 2.0;             ///< how far its signal reaches
};

/// Everything static, as given (the World validates it through StaticMap).
struct StaticMapConfig {
  FieldConfig field;                      ///< size and walls
  std::vector<ObstacleConfig> obstacles;  ///< static polygons
  std::vector<TrackConfig> tracks;        ///< floor tape
  std::vector<BeaconConfig> beacons;      ///< active targets
};

/// Index of each boundary wall in wall_segments() and in collision reports.
enum WallSide : int { kWallBottom = 0, kWallRight = 1, kWallTop = 2, kWallLeft = 3 };

/// The validated static world. Immutable once built.
class StaticMap {
 public:
  /// Validates and normalises `config` (drops a repeated closing vertex). Throws
  /// std::invalid_argument naming the offending item ("obstacle 2 (pillar): vertex 1 is
  /// not finite") on non-finite numbers, non-positive sizes, polygons with fewer than
  /// three vertices, zero area or crossing edges, tracks with fewer than two points,
  /// beacons with a bad aperture or range, or two beacons with one ID.
  explicit StaticMap(StaticMapConfig config = {});

  /// The field's size and whether it is walled.
  const FieldConfig& field() const { return config_.field; }
  /// Static obstacles, in configuration order (their index names them in events).
  std::span<const ObstacleConfig> obstacles() const { return config_.obstacles; }
  /// Floor tracks, in configuration order.
  std::span<const TrackConfig> tracks() const { return config_.tracks; }
  /// IR beacons, in configuration order (the direction finder reports them so).
  std::span<const BeaconConfig> beacons() const { return config_.beacons; }
  /// The whole validated configuration (for displays, which draw it once).
  const StaticMapConfig& config() const { return config_; }

  /// The four boundary walls as segments, indexed by WallSide (present even when the
  /// field has no walls; check field().boundary_walls).
  std::array<std::array<Vec2, 2>, 4> wall_segments() const;

  /// Bounding box of obstacle `index`'s vertices.
  const Box& obstacle_box(std::size_t index) const { return obstacle_boxes_[index]; }

  /// Index of an obstacle whose interior contains p, or -1.
  int obstacle_containing(Vec2 p) const;

  /// Bounding box of the field and of everything on it (obstacles, tracks with their
  /// width, beacons).
  Box extent() const;

 private:
  StaticMapConfig config_;
  std::vector<Box> obstacle_boxes_;
};

}  // namespace rilbed::environment
