// The collision server (paper 000 §6.2): after every substep of motion it removes every
// overlap between robots, static geometry and moving obstacles by positional correction,
// and it turns contacts into per-episode collision events.
//
// Rules:
// - A virtual robot and a wall or static obstacle: the robot is pushed out along the
//   contact normal until it touches. If its centre crossed a segment during the substep
//   (a fast robot, or a push), it is put back on the side it came from.
// - Two virtual robots: each moves half the overlap, apart along the line of centres.
// - Outlines: robots with a convex outline are tested against everything by the
//   separating-axis test and pushed out along its axis of least overlap, like discs
//   (translation only: a collision does not turn a robot). Discs keep their own path.
// - A virtual and a real robot: the virtual one moves the whole overlap; nothing virtual
//   ever moves a real robot. Two real robots are left alone (the real world decides).
// - A moving obstacle and a virtual robot: the robot is pushed out. A moving obstacle
//   and a real robot: the obstacle is pushed back and its velocity reflected.
// - A moving obstacle and a wall or static obstacle: pushed out and its velocity
//   reflected (elastic bounce: the overshoot is mirrored).
// The rules are applied in passes (Gauss–Seidel: each correction sees the previous ones)
// until a pass finds nothing to correct; each later pass only revisits bodies moved in
// the pass before. If max_passes is reached with overlaps left (a robot pinned in a
// crowd), every body still overlapping is put back where its substep started (a free
// place), repeatedly, until none overlaps: a virtual robot is never left overlapping
// another robot, an obstacle or a wall, except when real robots or a real robot and a
// wall squeeze it (the real world does not know about it).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "core/worker_pool.hpp"
#include "environment/body.hpp"
#include "environment/body_shape.hpp"
#include "environment/collision_event.hpp"
#include "environment/moving_obstacle.hpp"
#include "environment/segment_index.hpp"
#include "environment/spatial_grid.hpp"

namespace rilbed::environment {

/// Knobs of the resolver.
struct CollisionConfig {
  /// Most correction passes per substep before the fallback. A pass after the first
  /// only revisits the bodies moved in the pass before, so extra passes are cheap; a
  /// robot squeezed between a wall and another robot halves its overlap per pass, so
  /// reaching the tolerance from a centimetre takes about 25.
  int max_passes = 32;
  /// Surfaces closer than this count as touching for the contact episodes (so that a
  /// robot resting against a wall stays in one episode). Metres.
  double contact_margin_m = 1e-4;
  /// Overlaps up to this are left alone (floating-point slack). Metres.
  double tolerance_m = 1e-9;
  /// Find the robots that may touch anything first (on the workers, when set) and visit
  /// only those, and those a push brings near something, in the first pass; false visits
  /// every robot. The same results either way (a test compares them); true is faster.
  bool search_ahead = true;
};

/// What the resolver works on, by reference: the World's arrays.
struct CollisionScene {
  std::span<Body> bodies;            ///< robots, by slot
  std::span<const int> body_ids;     ///< robot id of each slot, for the events
  SpatialGrid& grid;                 ///< bodies hashed by cell; kept current by the resolver
  const SegmentIndex& statics;       ///< walls and obstacle edges
  std::span<MovingObstacle> movers;  ///< by index
  double max_body_radius_m = 0.0;
  /// The slots by ascending robot id (each once), or empty when slots are in id order.
  /// Overlaps are corrected robot after robot in this order, and a robot's neighbours in
  /// id order too, so that the results depend on the ids alone, not on how the slots are
  /// numbered (the World renumbers them by place).
  std::span<const std::uint32_t> id_order;
  /// The outlines bodies point into (Body::outline), turned to their bodies' headings at
  /// the substep's end (the fallback may turn one back: BodyOutline::turn_back); empty
  /// when every body is a disc.
  std::span<BodyOutline> outlines = {};
};

/// Resolves overlaps and records contact episodes. Keeps scratch buffers between calls
/// (no allocation per step once they have grown). Not thread-safe.
class CollisionResolver {
 public:
  explicit CollisionResolver(CollisionConfig config = {});

  /// The knobs it was made with.
  const CollisionConfig& config() const { return config_; }

  /// Starts a step: forgets the contacts of the previous step's substeps.
  void begin_step();
  /// Resolves the overlaps after one substep of motion that ended at t_us. Bodies'
  /// previous_m (and movers' previous_m) must hold their positions at the substep's start.
  void resolve(CollisionScene& scene, TimeUs t_us);
  /// Ends the step: the pairs in contact during this step that were not in contact
  /// during the previous step become events, sorted by time, then parties.
  std::span<const CollisionEvent> end_step();
  /// Looks for the robots that may be in contact on `pool`'s threads (null: on the
  /// caller's); the resolution itself stays on the caller's thread. Same results.
  void set_workers(core::WorkerPool* pool) { workers_ = pool; }
  /// The events of the last ended step.
  std::span<const CollisionEvent> events() const { return events_; }
  /// The bodies (indices into the scene's) whose positions the last resolve() changed,
  /// some maybe more than once: those whose step-end pose a caller set before it must set
  /// again.
  std::span<const int> pushed() const { return pushed_; }

 private:
  struct ContactRecord {
    BodyRef first;
    BodyRef second;
    TimeUs t_us;
  };
  using Pair = std::pair<BodyRef, BodyRef>;

  void record(BodyRef a, BodyRef b);
  void record_robot_pair(const CollisionScene& s, std::size_t i, std::size_t j);
  bool robots_vs_robots(CollisionScene& s);
  bool robots_vs_movers(CollisionScene& s);
  bool robots_vs_statics(CollisionScene& s);
  bool movers_vs_statics(CollisionScene& s);
  void mark_moved(CollisionScene& s, std::size_t body);
  bool body_overlaps(const CollisionScene& s, std::size_t i) const;
  void find_contacts_ahead(const CollisionScene& s);
  bool near_another_robot(const CollisionScene& s, std::size_t i) const;
  bool near_a_static(const CollisionScene& s, std::size_t i) const;
  void mark_near_dirty(const CollisionScene& s, std::size_t moved);
  bool mover_overlaps(const CollisionScene& s, std::size_t m) const;
  template <class Visit>
  void for_each_by_id(const CollisionScene& s, Visit&& visit) const;
  std::span<const std::uint32_t> robots_in_box_by_id(const CollisionScene& s, const Box& box);
  void fall_back(CollisionScene& s);

  CollisionConfig config_;
  TimeUs now_us_ = 0;
  std::vector<ContactRecord> contacts_;
  std::vector<Pair> previous_pairs_;
  std::vector<Pair> current_pairs_;
  std::vector<CollisionEvent> events_;
  // Active-set bookkeeping: bodies to visit in this pass, bodies moved in this pass.
  std::vector<int> active_;
  std::vector<int> moved_list_;
  std::vector<int> pushed_;  // see pushed()
  std::vector<std::uint8_t> is_active_;
  std::vector<std::uint8_t> moved_;
  std::vector<std::uint8_t> reverted_;
  bool all_active_ = true;
  // The first pass visits only the robots that may touch something (found beforehand,
  // on the workers when set) and those that a push in the pass brought near something.
  std::vector<std::uint8_t> near_robot_;    // at the pass's start: another robot within contact
  std::vector<std::uint8_t> near_static_;   // at the pass's start: a wall or obstacle within contact, or crossed
  std::vector<std::uint8_t> dirty_;         // near a robot moved in this pass
  std::vector<std::uint32_t> in_box_;       // scratch of robots_in_box_by_id
  std::vector<std::uint32_t> in_segments_;  // scratch: segments_in_box
  core::WorkerPool* workers_ = nullptr;
};

}  // namespace rilbed::environment
