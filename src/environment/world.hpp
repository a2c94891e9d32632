// The world model (paper 000 §6.1, world server and collision server together): the
// static map, the robots (virtual ones driven by their wheel commands, real ones placed
// from outside), moving obstacles, collisions, and every robot's virtual sensors.
//
// A step moves virtual robots along exact arcs and moving obstacles in straight lines,
// in as many equal substeps as the fastest body needs to travel at most
// max_substep_travel_m per substep, and resolves collisions after each substep
// (CollisionResolver). Robots and static segments are hashed in uniform grids, so a
// step costs about linearly in the number of robots at constant density.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include "core/time.hpp"
#include "core/worker_pool.hpp"
#include "environment/collision_resolver.hpp"
#include "environment/robot_state.hpp"
#include "environment/scene.hpp"
#include "environment/sensor_readings.hpp"
#include "environment/static_map.hpp"
#include "environment/world_snapshot.hpp"

namespace rilbed::environment {

/// Knobs of the world.
struct WorldConfig {
  /// Side of the grid cells that hash robots and static segments, metres; 0 picks 0.25 m
  /// (more than a Khepera's diameter plus its IR range, so a query spans at most 2 x 2
  /// cells). Smaller cells mean fewer candidates per query but more cells to visit and a
  /// bigger cell table (0.1 m was 5 % slower at 10,000 and 100,000 Kheperas); far from a
  /// Khepera's scale, set it to about twice the largest robot diameter plus the longest
  /// proximity range. Results do not depend on it.
  double cell_size_m = 0.0;
  /// Upper bound on the cell count; cells grow beyond cell_size_m on huge fields. (The
  /// grids' per-cell arrays pad the cells to whole blocks of 8 x 8.)
  std::size_t max_grid_cells = std::size_t{1} << 22;
  /// Largest distance a body may travel in one substep, metres; 0 means the smallest
  /// robot radius, which keeps two robots from passing through each other. Smaller is
  /// finer and slower (the number of substeps per step grows as 1 / this).
  double max_substep_travel_m = 0.0;
  /// Collision resolution (passes, contact margin for events, tolerance).
  CollisionConfig collision;
  /// The world's clock at construction.
  TimeUs start_t_us = 0;
  /// Seed of every noise in the world (sensors, wheel slip). Each robot's noise at each
  /// instant is drawn from its own stream keyed by (seed, robot id, time), so results do
  /// not depend on the order in which robots sense or on threads.
  std::uint64_t noise_seed = 0;
  /// Every this many steps the world renumbers its robots' slots by where they are
  /// (tiles of the grid), so that every per-robot loop (sensing, motion, the contact
  /// search) walks memory in order and finds a robot's neighbours just visited, still in
  /// cache; 0 renumbers only when robots are added or removed. Results do not depend on
  /// it. Costs a sort and a move of every robot's records each time.
  int reorder_every_steps = 20;
};

/// Wall time the world's steps took, summed since it was built, seconds.
struct WorldStepTimes {
  double integration_s = 0.0;  ///< wheel speeds, arcs, moving bodies, renumbering the slots by place
  double collisions_s = 0.0;   ///< CollisionResolver, every substep
};

/// The world. Owns everything in it. Not thread-safe for changes: one thread adds,
/// removes, sets, steps and sweeps (sense_ahead). The const members (sense, sense_all,
/// snapshot, robot, ...) keep no scratch state, so several threads may call them at once
/// between steps; max_overlap_m is the exception when workers are set (it runs on them:
/// call it from the stepping thread, outside any worker loop).
class World {
 public:
  /// Builds the world around a validated static map. Throws std::invalid_argument for a
  /// bad map (see StaticMap) or bad config values.
  explicit World(StaticMapConfig map, WorldConfig config = {});

  /// The static map (send it to displays once).
  const StaticMap& map() const { return map_; }
  /// The knobs the world was made with.
  const WorldConfig& config() const { return config_; }
  /// The world's clock, microseconds.
  TimeUs time_us() const { return t_us_; }

  /// Adds a robot. Throws std::invalid_argument naming it ("robot 3: ...") for a
  /// duplicate id, non-finite pose, non-positive radius or wheel base, bad noise or
  /// sensor settings, and, for a virtual robot, a placement overlapping a boundary wall,
  /// a static obstacle, a moving obstacle or another robot. A real robot may be placed
  /// anywhere (the camera saw it there); virtual robots make way for it.
  void add_robot(const RobotConfig& config);
  /// Removes a robot. Throws std::invalid_argument for an unknown id.
  void remove_robot(int id);
  /// Robot `id`'s outline in its own frame (counter-clockwise), or empty for a disc.
  /// Throws std::invalid_argument for an unknown id.
  std::span<const Vec2> outline_m(int id) const;
  /// Whether sensor models draw what they see (SensorReadings::marks): for displays only,
  /// off by default.
  void set_collect_marks(bool on) { collect_marks_ = on; }
  /// Whether a robot with this id is in the world.
  bool has_robot(int id) const { return slot_of_.contains(id); }
  /// The robot with this id. Throws std::invalid_argument for an unknown id. The
  /// reference stays valid until a robot is added or removed.
  const RobotState& robot(int id) const;
  /// All robots, in slot order: by place, renumbered as they move (see
  /// WorldConfig::reorder_every_steps), the same for the same calls. For a stable order
  /// use ids_in_added_order() or sort by id.
  std::span<const RobotState> robots() const { return robots_; }
  /// The robots' ids in the order they were added (removal moves the last into the gap).
  std::span<const int> ids_in_added_order() const { return added_order_; }
  /// Robot `id`'s current pose, as robot(id).pose. Throws std::invalid_argument for an
  /// unknown id. Kept in the order robots were added, apart from the slots that move by
  /// place: agents that ask in id order read memory in order.
  Pose2 pose(int id) const { return poses_[added_index(id)]; }
  /// Every robot's pose(), by index in ids_in_added_order() (valid until the world changes).
  std::span<const Pose2> poses_in_added_order() const { return poses_; }
  /// A hint, no effect on results, for an agent's step a few agents ahead: asks the CPU
  /// for robot `id`'s entry in the id table, through which the step finds the robot's
  /// stored readings, pose and wheel commands. (Those are in the agents' order, which the
  /// CPU's own prefetcher follows; the ids need not be.) Unknown ids: nothing.
  void prefetch(int id) const;

  /// Sets a robot's wheel commands, pulses per 10 ms, clamped to [-127, 127] as the
  /// Khepera firmware does. Used by the next step (virtual robots); kept for display for
  /// real ones. Throws std::invalid_argument for an unknown id.
  void set_wheel_speeds(int id, int left_units, int right_units);
  /// Robot `id`'s wheel commands as last set (clamped). Kept in the order robots were
  /// added, like pose(): agents that drive in id order write memory in order (in the
  /// robots' table, by place, each write was a cache miss at 100,000 robots). Throws
  /// std::invalid_argument for an unknown id.
  WheelUnits wheel_speeds(int id) const { return commands_[added_index(id)]; }
  /// Robot `id`'s sensors as configured (RobotConfig::sensors). Throws
  /// std::invalid_argument for an unknown id.
  const SensorSuiteConfig& sensor_config(int id) const { return suite_configs_[suite_of_[slot(id)]]; }
  /// Sets a real robot's pose as observed (by the camera) at t_us. Throws
  /// std::invalid_argument for a virtual robot or a non-finite pose.
  void set_observed_pose(int id, Pose2 pose, TimeUs t_us);
  /// Sets a robot's wheel counters (the Khepera's `G` command).
  void set_odometer(int id, OdometryReading counters);

  /// Adds a moving obstacle and returns its index (used in collision events). Throws
  /// std::invalid_argument for a bad configuration or a placement overlapping a wall, a
  /// static obstacle or a robot.
  int add_moving_obstacle(const MovingObstacleConfig& config);
  /// The moving obstacles, by index.
  std::span<const MovingObstacle> moving_obstacles() const { return movers_; }

  /// Advances the world by dt_us >= 0: virtual robots drive (each robot's wheel slip
  /// drawn from its stream for the step's start time), moving obstacles drift, collisions
  /// are resolved, the clock advances. Returns the collision events that began during
  /// this step (valid until the next step). dt_us == 0 does nothing. Same seed and same
  /// calls give the same world, on any standard library.
  std::span<const CollisionEvent> step(TimeUs dt_us);
  /// Moves the robots of a step, and looks for their contacts, on `pool`'s threads from
  /// now on (null: this thread only). Collisions are still resolved on the stepping
  /// thread. Results are the same for any number of threads. The pool must outlive the
  /// steps.
  void set_workers(core::WorkerPool* pool) {
    workers_ = pool;
    resolver_.set_workers(pool);
  }

  /// How long the steps so far took, split (a few clock reads per step and substep).
  const WorldStepTimes& step_times() const { return step_times_; }
  /// The events returned by the last step.
  std::span<const CollisionEvent> last_collisions() const { return resolver_.events(); }

  /// Reads every virtual sensor robot `id` carries, stamped t_us. The noise comes from
  /// the robot's stream for t_us: reading twice at one instant gives the same values.
  /// Works for real robots too: their virtual sensors see virtual and real robots,
  /// walls and obstacles. The odometer is filled for virtual robots only (a real robot's
  /// counters come from its link). Throws std::invalid_argument for an unknown id.
  SensorReadings sense(int id, TimeUs t_us) const;
  /// As sense(id, t_us), with the noise drawn from `rng` instead of the robot's stream
  /// (tests that want many independent readings of one instant).
  SensorReadings sense(int id, TimeUs t_us, NoiseRng& rng) const;
  /// As sense(id, t_us), into `out` (its buffers reused, so a caller that keeps `out`
  /// allocates nothing).
  void sense_into(int id, TimeUs t_us, SensorReadings& out) const;
  /// Reads every robot's sensors into out[i] for robots()[i] (out is resized; its
  /// elements' buffers are reused).
  void sense_all(TimeUs t_us, std::vector<SensorReadings>& out) const;
  /// Reads every robot's sensors at t_us into the world's own store, robot after robot
  /// in slot order, i.e. by place (on the workers when set), so that sense(id, t_us) and
  /// sense_into(id, t_us) return the stored reading until the world next changes. The
  /// same readings as computed one by one (each robot's noise has its own stream): a
  /// sweep only keeps neighbours in cache and spreads the work.
  void sense_ahead(TimeUs t_us);

  /// A copy of the moving state (robots in the order they were added), with the last
  /// step's events.
  WorldSnapshot snapshot() const;

  /// Largest overlap, metres, between a virtual robot and anything (another robot, a
  /// wall or static obstacle, a moving obstacle); 0 when none. A check for tests and
  /// benchmarks: O(robots), on the workers when set.
  double max_overlap_m() const;

  /// The read-only view sensors use (valid until the world changes).
  Scene scene() const;

 private:
  // Per-step motion of one virtual robot: its substep displacement in its own frame and
  // the rotation per substep (exact arc, applied by rotating a unit heading vector, so
  // that a substep costs no trigonometry).
  struct Motion {
    Vec2 local_step_m;
    double cos_turn = 1.0, sin_turn = 0.0;
    Vec2 heading;  // unit, current substep
    double end_heading_rad = 0.0;
  };

  std::size_t slot(int id) const;
  void sense_slot(const Scene& scene, std::size_t s, TimeUs t_us, SensorReadings& out) const;
  std::string label(int id) const { return "robot " + std::to_string(id); }
  // `outline`: the body's outline turned to its heading, or null for the disc.
  void check_placement_free(const std::string& what, Vec2 position_m, double radius_m, const BodyOutline* outline,
                            int exclude_slot) const;
  // Turns every outline to its robot's heading after a substep's move (`substeps`: the
  // step's count, which says where virtual robots' current headings are).
  void turn_outlines(int substeps);
  void refresh_outline_slots();
  // After a substep's resolution: robots whose outline the fallback turned back turn back
  // too (the rest of the step from there); finish_turned_back sets their step-end poses.
  void follow_turned_back_outlines(int substeps);
  void finish_turned_back(int substeps);
  const BodyOutline* outline_of(const Body& b) const {
    return b.outline >= 0 ? &outlines_[static_cast<std::size_t>(b.outline)] : nullptr;
  }
  void refresh_max_radius();
  // Sets robot `id`'s slot in the dense table (-1: none); false when the id has no
  // entry there (too large, or negative), and the hash map must hold its slot.
  bool set_dense_slot(int id, std::int32_t s);
  // Records robot `id`'s index in added_order_ in the dense table (if it has an entry).
  void set_dense_added(int id, std::uint32_t added);
  // Robot `id`'s index in added_order_ (throws like slot()).
  std::size_t added_index(int id) const;
  std::uint32_t pooled_suite(const SensorSuiteConfig& config, SensorSuite&& suite);
  double substep_limit_m() const;
  // Calls body(begin, end) over robot slots [0, robots), on the workers when set.
  template <class Body>
  void for_robot_slots(Body&& body) {
    if (workers_ && workers_->threads() > 1 && robots_.size() > 1)
      workers_->for_chunks(robots_.size(), body);
    else
      body(0, robots_.size());
  }
  // Each virtual robot's wheel speeds for a step of dt_s (step_wheels_mps_) and odometer;
  // returns the longest distance one of them travels.
  double start_wheels(std::size_t begin, std::size_t end, double dt_s);
  // Sets motion_[i] for substeps of h_s seconds each, from the wheels' ground speeds.
  void set_arc(std::size_t i, Vec2 wheels_mps, double wheel_base_m, double h_s, int substeps);
  // One of several substeps of a step (motion_ set by set_arc) for slots [begin, end);
  // `last`: the step's last, which sets the end poses (finish_move).
  void move_substep(std::size_t begin, std::size_t end, bool last, TimeUs end_t_us);
  // A step of dt_s taken as one substep (the usual case): each robot's arc, move and end
  // pose in one pass over slots [begin, end), with no Motion stored and read again.
  void move_whole_step(std::size_t begin, std::size_t end, double dt_s, TimeUs end_t_us);
  // The end of virtual robot i's move in a step ending at end_t_us: its pose (and poses_),
  // heading end_heading_rad, and its heading vector `heading`, renormalised. `end`: the end
  // of the caller's run of slots.
  void finish_move(std::size_t i, std::size_t end, TimeUs end_t_us, Vec2 heading, double end_heading_rad);
  // What can change a reading happened: sense_ahead's store is stale.
  void changed() { ahead_valid_ = false; }
  void renumber_by_place();
  template <class T>
  void permute(std::vector<T>& items, std::vector<T>& scratch);
  double overlap_of(std::size_t slot) const;

  WorldConfig config_;
  StaticMap map_;
  GridGeometry grid_geometry_;
  SegmentIndex statics_;
  SegmentIndex tracks_;
  SpatialGrid grid_;
  // Robots, in parallel arrays by slot.
  std::vector<RobotState> robots_;
  std::vector<Body> bodies_;
  std::vector<int> ids_;
  std::vector<std::uint32_t> suite_of_;           // per slot: its suite in suite_pool_
  std::vector<SensorSuite> suite_pool_;           // the distinct suites
  std::vector<SensorSuiteConfig> suite_configs_;  // their configurations
  std::vector<Motion> motion_;                    // a step's substeps (only when it has more than one)
  std::vector<Vec2> step_wheels_mps_;             // per slot: left (x) and right (y) ground speeds over the step
  std::vector<Vec2> headings_;  // (cos, sin) of each robot's heading: computed when placed or seen, rotated by each
                                // step with the pose (equal to a few ulps)
  // Every robot's id (has_robot); its slot, which slot() reads only for ids without a
  // dense entry in by_id_, is kept current for those only (renumbering does not touch the
  // others' entries).
  std::unordered_map<int, std::size_t> slot_of_;
  // Per small id: its slot (-1 for none) and its index in added_order_. An agent reads
  // both each step in id order: one sequential table, where added_of_slot_[slot] was a
  // random read (a cache miss each at 100,000 robots).
  struct IdEntry {
    std::int32_t slot = -1;
    std::uint32_t added = 0;
  };
  std::vector<IdEntry> by_id_;
  double max_radius_m_ = 0.0;
  double min_radius_m_ = 0.0;  // the smallest body's inner radius (a disc's radius), for substeps
  // Outlines (Body::outline indexes them; a removed robot's stays unused) and the slots
  // of the bodies that have one, in slot order.
  std::vector<BodyOutline> outlines_;
  std::vector<std::uint32_t> outline_slots_;
  std::vector<std::uint32_t> turned_back_;  // this step's, by slot (maybe more than once)
  std::vector<MovingObstacle> movers_;
  CollisionResolver resolver_;
  WorldStepTimes step_times_;
  core::WorkerPool* workers_ = nullptr;
  // sense_ahead's readings in the order robots were added (what agents read in id order),
  // each on cache lines of its own (threads of the sweep write them in any order).
  // One robot's readings of the last sweep, packed in one cache line (the IR ring, the
  // odometry, and flags): the store is written by the sweep and read by the agents in
  // another order, and whole SensorReadings (three lines, mostly empty lists) made it a
  // fifth of the memory traffic at 100,000 robots. The lists (ranges, beacons, track)
  // live apart, in ahead_lists_, sized only when some robot's sensors fill them. Whole
  // lines each, so that threads writing neighbouring records do not share a line.
  struct alignas(64) StoredReadings {
    TimeUs t_us = 0;
    ProximityValues proximity{};
    OdometryReading odometry;
    bool has_proximity = false;
    bool has_odometry = false;
    bool has_lists = false;  // its lists are in ahead_lists_ (else they are empty)
  };
  static_assert(sizeof(StoredReadings) == 64, "one cache line per robot");
  struct StoredLists {
    std::vector<RangeReading> ranges;
    std::vector<BeaconSighting> beacons;
    std::vector<int> track;
    std::vector<ModelReading> models;
    std::vector<SensorMark> marks;
  };
  // Packs `readings` as robot (added index) `added`'s record.
  void store_readings(std::size_t added, SensorReadings& readings);
  // mobiles_ from the robots' and moving obstacles' poses, when a robot carries a sensor model.
  void refresh_mobiles() const;
  mutable std::vector<MobilePose> mobiles_;  // what sensor models see of every mobile object (scene().mobiles)
  bool has_models_ = false;                  // some suite carries a sensor model
  bool collect_marks_ = false;               // sensor models draw (set_collect_marks)
  bool models_concurrent_ = true;            // every suite's models may sense for two robots at once
  std::vector<StoredReadings> ahead_;
  std::vector<StoredLists> ahead_lists_;      // by added index; empty unless a suite has lists
  std::vector<std::uint32_t> added_of_slot_;  // per slot: its robot's index in added_order_
  std::vector<Pose2> poses_;                  // each robot's pose, by index in added_order_
  std::vector<WheelUnits> commands_;          // each robot's wheel commands, by index in added_order_
  std::vector<std::unique_ptr<DriveModel>>
      drives_;                     // each robot's drive model, by index in added_order_; null: built in
  bool drives_concurrent_ = true;  // every drive model may run for two robots at once
  TimeUs ahead_t_us_ = 0;
  bool ahead_valid_ = false;
  long steps_ = 0;
  bool renumber_due_ = true;              // robots were added or removed since the last renumbering
  std::vector<int> added_order_;          // ids in the order added (removal moves the last into the gap)
  std::vector<std::uint32_t> id_order_;   // slots by ascending robot id (the collision resolver's order)
  std::vector<std::uint32_t> new_order_;  // scratch of renumber_by_place: old slot of each new slot
  struct RenumberKey {
    std::uint64_t place;  // grid cell
    int id;
    std::uint32_t slot;
  };
  std::vector<RenumberKey> renumber_keys_;  // scratch of renumber_by_place
  // Kept buffers of renumber_by_place's moves (the previous arrays, moved from).
  std::vector<RobotState> robots_scratch_;
  std::vector<Body> bodies_scratch_;
  std::vector<int> ints_scratch_;
  std::vector<std::uint32_t> slots_scratch_;
  std::vector<Vec2> headings_scratch_;
  TimeUs t_us_ = 0;
};

}  // namespace rilbed::environment
