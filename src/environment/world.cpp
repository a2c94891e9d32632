#include "environment/world.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>

#include "environment/random.hpp"

namespace rilbed::environment {

namespace {

// About the widest box a Khepera's sensing or contact query asks for (two radii and the
// IR range, 0.105 m) and more: a query then spans at most 2 x 2 cells of mostly one
// robot each. At 0.1 m, 3 x 3 cells of 0.04 robots each, and at 100,000 robots a cell
// table of 9 MB that every query pass walked.
constexpr double kDefaultCell_m = 0.25;
// How many robots ahead the sensor sweep asks for the record it will write (sense_ahead).
constexpr std::size_t kStorePrefetch = 8;

bool finite(Vec2 v) { return std::isfinite(v.x) && std::isfinite(v.y); }

void validate_config(const WorldConfig& c) {
  if (!std::isfinite(c.cell_size_m) || c.cell_size_m < 0.0)
    throw std::invalid_argument("world: cell_size_m must be >= 0");
  if (c.max_grid_cells < 1) throw std::invalid_argument("world: max_grid_cells must be >= 1");
  if (!std::isfinite(c.max_substep_travel_m) || c.max_substep_travel_m < 0.0)
    throw std::invalid_argument("world: max_substep_travel_m must be >= 0");
  if (c.collision.max_passes < 1) throw std::invalid_argument("world: collision.max_passes must be >= 1");
  if (!std::isfinite(c.collision.contact_margin_m) || c.collision.contact_margin_m < 0.0)
    throw std::invalid_argument("world: collision.contact_margin_m must be >= 0");
  if (!std::isfinite(c.collision.tolerance_m) || c.collision.tolerance_m < 0.0)
    throw std::invalid_argument("world: collision.tolerance_m must be >= 0");
}

GridGeometry make_grid(const StaticMap& map, const WorldConfig& config) {
  const double cell = config.cell_size_m > 0.0 ? config.cell_size_m : kDefaultCell_m;
  Box box = map.extent();
  // One spare cell around everything, so that bodies just outside still hash apart.
  box.lo_m = box.lo_m - Vec2{cell, cell};
  box.hi_m = box.hi_m + Vec2{cell, cell};
  return GridGeometry::covering(box, cell, config.max_grid_cells);
}

std::vector<IndexedSegment> static_segments(const StaticMap& map) {
  std::vector<IndexedSegment> segments;
  if (map.field().boundary_walls) {
    const auto walls = map.wall_segments();
    for (int k = 0; k < 4; ++k) segments.push_back({walls[k][0], walls[k][1], {BodyKind::kWall, k}, 0.0});
  }
  for (std::size_t i = 0; i < map.obstacles().size(); ++i) {
    const auto& v = map.obstacles()[i].vertices_m;
    for (std::size_t k = 0; k < v.size(); ++k)
      segments.push_back({v[k], v[(k + 1) % v.size()], {BodyKind::kObstacle, static_cast<int>(i)}, 0.0});
  }
  return segments;
}

std::vector<IndexedSegment> track_segments(const StaticMap& map) {
  std::vector<IndexedSegment> segments;
  for (std::size_t i = 0; i < map.tracks().size(); ++i) {
    const TrackConfig& t = map.tracks()[i];
    const BodyRef owner{BodyKind::kObstacle, static_cast<int>(i)};
    for (std::size_t k = 0; k + 1 < t.points_m.size(); ++k)
      segments.push_back({t.points_m[k], t.points_m[k + 1], owner, 0.5 * t.width_m});
    if (t.closed) segments.push_back({t.points_m.back(), t.points_m.front(), owner, 0.5 * t.width_m});
  }
  return segments;
}

}  // namespace

World::World(StaticMapConfig map, WorldConfig config)
    : config_((validate_config(config), config)),
      map_(std::move(map)),
      grid_geometry_(make_grid(map_, config_)),
      statics_(grid_geometry_, static_segments(map_)),
      tracks_(grid_geometry_, track_segments(map_)),
      grid_(grid_geometry_),
      resolver_(config_.collision),
      t_us_(config_.start_t_us) {}

std::size_t World::slot(int id) const {
  // Small ids (the usual 1..N) through the dense table: every agent looks its robot up
  // several times a step, and a hash lookup was a cache miss each at 10,000 robots.
  if (id >= 0 && static_cast<std::size_t>(id) < by_id_.size()) {
    const std::int32_t s = by_id_[static_cast<std::size_t>(id)].slot;
    if (s >= 0) return static_cast<std::size_t>(s);
  }
  const auto it = slot_of_.find(id);
  if (it == slot_of_.end()) throw std::invalid_argument("no robot with id " + std::to_string(id));
  return it->second;
}

const RobotState& World::robot(int id) const { return robots_[slot(id)]; }

Scene World::scene() const {
  return Scene{statics_, tracks_, bodies_, grid_, movers_, map_.beacons(), max_radius_m_, mobiles_};
}

void World::refresh_mobiles() const {
  if (!has_models_) return;
  mobiles_.resize(added_order_.size() + movers_.size());
  for (std::size_t k = 0; k < added_order_.size(); ++k) {
    const Pose2& p = poses_[k];
    mobiles_[k] = {added_order_[k], p.position_m.x, p.position_m.y, p.heading_rad};
  }
  for (std::size_t m = 0; m < movers_.size(); ++m) {
    const Vec2 p = movers_[m].position_m();
    mobiles_[added_order_.size() + m] = {-1 - static_cast<int>(m), p.x, p.y, 0.0};
  }
}

void World::check_placement_free(const std::string& what, Vec2 p, double r, const BodyOutline* outline,
                                 int exclude_slot) const {
  const double tol = config_.collision.tolerance_m;
  OutlineBuffer buffer;
  const BodyShape shape = place_body(p, r, outline, buffer);
  if (map_.field().boundary_walls) {
    const FieldConfig& f = map_.field();
    const char* wall = nullptr;
    const double left = p.x - shape_reach_against(shape, {1.0, 0.0});
    const double right = p.x + shape_reach_against(shape, {-1.0, 0.0});
    const double bottom = p.y - shape_reach_against(shape, {0.0, 1.0});
    const double top = p.y + shape_reach_against(shape, {0.0, -1.0});
    if (left < -tol)
      wall = "the left wall";
    else if (right > f.width_m + tol)
      wall = "the right wall";
    else if (bottom < -tol)
      wall = "the bottom wall";
    else if (top > f.height_m + tol)
      wall = "the top wall";
    if (wall) throw std::invalid_argument(what + ": placed overlapping " + wall);
  }
  if (const int inside = map_.obstacle_containing(p); inside >= 0)
    throw std::invalid_argument(what + ": placed inside obstacle " + std::to_string(inside));
  statics_.for_each_in_box(box_around(p, r), [&](const IndexedSegment& seg) {
    if (shape_segment_contact(shape, seg.a_m, seg.b_m).separation_m < -tol)
      throw std::invalid_argument(what + ": placed overlapping " + to_string(seg.owner));
  });
  grid_.for_each_in_box(box_around(p, r + max_radius_m_), [&](int j) {
    if (j == exclude_slot) return;
    const Body& b = bodies_[static_cast<std::size_t>(j)];
    const double sum = r + b.radius_m - tol;
    if (distance_sq(p, b.position_m) >= sum * sum) return;
    OutlineBuffer other;
    if ((outline || b.outline >= 0) &&
        shape_shape_contact(shape, place_body(b.position_m, b.radius_m, outline_of(b), other)).separation_m >= -tol)
      return;
    throw std::invalid_argument(what + ": placed overlapping robot " +
                                std::to_string(ids_[static_cast<std::size_t>(j)]));
  });
  for (std::size_t m = 0; m < movers_.size(); ++m) {
    if (shape_mover_contact(shape, movers_[m]).separation_m < -tol)
      throw std::invalid_argument(what + ": placed overlapping moving obstacle " + std::to_string(m));
  }
}

void World::add_robot(const RobotConfig& c) {
  const std::string what = label(c.id);
  if (slot_of_.contains(c.id)) throw std::invalid_argument(what + ": another robot has this id");
  if (!finite(c.pose.position_m) || !std::isfinite(c.pose.heading_rad))
    throw std::invalid_argument(what + ": pose is not finite");
  if (!std::isfinite(c.radius_m) || c.radius_m <= 0.0)
    throw std::invalid_argument(what + ": radius_m must be a positive number");
  if (!std::isfinite(c.wheel_base_m) || c.wheel_base_m <= 0.0)
    throw std::invalid_argument(what + ": wheel_base_m must be a positive number");
  const WheelNoiseConfig& n = c.noise;
  if (!std::isfinite(n.slip_sd) || n.slip_sd < 0.0) throw std::invalid_argument(what + ": noise.slip_sd must be >= 0");
  if (!std::isfinite(n.left_bias) || !std::isfinite(n.right_bias) || n.left_bias <= -1.0 || n.right_bias <= -1.0)
    throw std::invalid_argument(what + ": noise biases must be finite and above -1");
  SensorSuite suite(c.sensors, what);  // validates the sensors
  // An outline replaces the disc: its bounding radius is the body's for the broad phase.
  BodyOutline outline;
  double radius_m = c.radius_m, inner_radius_m = c.radius_m;
  if (!c.outline_m.empty()) {
    outline.local_m = checked_outline(c.outline_m, what);
    outline.heading = outline.start_heading = {std::cos(c.pose.heading_rad), std::sin(c.pose.heading_rad)};
    radius_m = outline_bounding_radius_m(outline.local_m);
    inner_radius_m = outline_inner_radius_m(outline.local_m);
  }
  const BodyOutline* placed_outline = c.outline_m.empty() ? nullptr : &outline;
  if (c.kind == RobotKind::kVirtual) check_placement_free(what, c.pose.position_m, radius_m, placed_outline, -1);

  // The robot's drive first: a model that refuses it leaves the world as it was.
  std::unique_ptr<DriveModel> drive;
  if (c.drive && c.kind == RobotKind::kVirtual) {
    try {
      drive = c.drive->make(c.id, c.wheel_base_m);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(what + ": " + e.what());
    }
  }
  RobotState state;
  state.id = c.id;
  state.kind = c.kind;
  state.pose = {c.pose.position_m, wrap_rad_pi(c.pose.heading_rad)};
  state.pose_t_us = t_us_;
  state.radius_m = radius_m;
  state.wheel_base_m = c.wheel_base_m;
  state.noise = c.noise;
  // Grow the parallel arrays first (geometrically, so that adding n robots costs O(n)) so
  // that a failed allocation leaves them in step. (The suite pool and the dense id table
  // may still allocate after the pushes; the id map stays the authority for lookups.)
  const std::size_t s = robots_.size();
  if (s == robots_.capacity()) {
    const std::size_t want = std::max<std::size_t>(16, 2 * s);
    robots_.reserve(want), bodies_.reserve(want), ids_.reserve(want), suite_of_.reserve(want), motion_.reserve(want);
    headings_.reserve(want), added_order_.reserve(want), added_of_slot_.reserve(want), poses_.reserve(want);
    commands_.reserve(want), drives_.reserve(want);
    slot_of_.reserve(want);
  }
  robots_.push_back(std::move(state));
  std::int32_t outline_index = -1;
  if (placed_outline) {
    outline_index = static_cast<std::int32_t>(outlines_.size());
    outlines_.push_back(std::move(outline));
    outline_slots_.push_back(static_cast<std::uint32_t>(s));
  }
  bodies_.push_back({c.pose.position_m, c.pose.position_m, radius_m, c.kind == RobotKind::kVirtual, outline_index});
  ids_.push_back(c.id);
  added_of_slot_.push_back(static_cast<std::uint32_t>(added_order_.size()));
  added_order_.push_back(c.id);
  poses_.push_back(robots_.back().pose);
  commands_.emplace_back();
  drives_.push_back(std::move(drive));
  drives_concurrent_ = drives_concurrent_ && (!c.drive || c.drive->concurrent());
  suite_of_.push_back(pooled_suite(c.sensors, std::move(suite)));
  motion_.emplace_back();
  slot_of_.emplace(c.id, s);
  const double heading_rad = robots_.back().pose.heading_rad;
  headings_.push_back({std::cos(heading_rad), std::sin(heading_rad)});
  set_dense_slot(c.id, static_cast<std::int32_t>(s));
  set_dense_added(c.id, added_of_slot_.back());
  grid_.push_back(c.pose.position_m);
  renumber_due_ = true;
  changed();
  // The new radius only (a full refresh made adding n robots cost O(n^2): 7 s for 100,000).
  max_radius_m_ = s == 0 ? radius_m : std::max(max_radius_m_, radius_m);
  min_radius_m_ = s == 0 ? inner_radius_m : std::min(min_radius_m_, inner_radius_m);
}

std::span<const Vec2> World::outline_m(int id) const {
  const BodyOutline* outline = outline_of(bodies_[slot(id)]);
  return outline ? std::span<const Vec2>(outline->local_m) : std::span<const Vec2>();
}

void World::refresh_outline_slots() {
  outline_slots_.clear();
  if (outlines_.empty()) return;
  for (std::size_t i = 0; i < bodies_.size(); ++i)
    if (bodies_[i].outline >= 0) outline_slots_.push_back(static_cast<std::uint32_t>(i));
}

void World::turn_outlines(int substeps) {
  for (const std::uint32_t i : outline_slots_) {
    const bool mid_step = substeps > 1 && robots_[i].kind == RobotKind::kVirtual;
    BodyOutline& outline = outlines_[static_cast<std::size_t>(bodies_[i].outline)];
    outline.turn_to(mid_step ? motion_[i].heading : headings_[i]);
  }
}

void World::follow_turned_back_outlines(int substeps) {
  for (const std::uint32_t i : outline_slots_) {
    BodyOutline& outline = outlines_[static_cast<std::size_t>(bodies_[i].outline)];
    if (!outline.turned_back) continue;
    outline.turned_back = false;
    if (substeps > 1) {
      // The rest of the step turns from where the robot was put back.
      Motion& m = motion_[i];
      m.heading = outline.heading;
      m.end_heading_rad -= std::atan2(m.sin_turn, m.cos_turn);
    }
    turned_back_.push_back(i);
  }
}

void World::finish_turned_back(int substeps) {
  for (const std::uint32_t i : turned_back_) {
    RobotState& r = robots_[i];
    const Vec2 h = substeps > 1 ? motion_[i].heading : outlines_[static_cast<std::size_t>(bodies_[i].outline)].heading;
    r.pose.heading_rad = wrap_rad_pi(substeps > 1 ? motion_[i].end_heading_rad : std::atan2(h.y, h.x));
    headings_[i] = h;
    poses_[added_of_slot_[i]].heading_rad = r.pose.heading_rad;
  }
  turned_back_.clear();
}

void World::remove_robot(int id) {
  const std::size_t s = slot(id);
  // Its place in the added order goes to the last added (as its slot goes to the last slot).
  const std::uint32_t place = added_of_slot_[s];
  const int last_added = added_order_.back();
  added_of_slot_[slot(last_added)] = place;
  set_dense_added(last_added, place);
  added_order_[place] = last_added;
  poses_[place] = poses_.back();
  commands_[place] = commands_.back();
  drives_[place] = std::move(drives_.back());
  added_order_.pop_back(), poses_.pop_back(), commands_.pop_back(), drives_.pop_back();
  const std::size_t last = robots_.size() - 1;
  if (s != last) {
    robots_[s] = std::move(robots_[last]);
    bodies_[s] = bodies_[last];
    ids_[s] = ids_[last];
    added_of_slot_[s] = added_of_slot_[last];
    suite_of_[s] = suite_of_[last];
    motion_[s] = motion_[last];
    headings_[s] = headings_[last];
    slot_of_[ids_[s]] = s;
    set_dense_slot(ids_[s], static_cast<std::int32_t>(s));
  }
  robots_.pop_back(), bodies_.pop_back(), ids_.pop_back(), suite_of_.pop_back(), motion_.pop_back(),
      headings_.pop_back();
  added_of_slot_.pop_back();
  slot_of_.erase(id);
  set_dense_slot(id, -1);
  renumber_due_ = true;
  changed();
  grid_.rebuild(bodies_.size(), [&](std::size_t i) { return bodies_[i].position_m; });
  refresh_outline_slots();
  refresh_max_radius();
}

std::uint32_t World::pooled_suite(const SensorSuiteConfig& config, SensorSuite&& suite) {
  // Robots of a scenario mostly carry the same sensors: one suite serves them all (a
  // suite is 360 bytes of configuration that every reading goes through).
  const std::size_t look_back = std::min<std::size_t>(suite_configs_.size(), 16);
  for (std::size_t k = suite_configs_.size(); k-- > suite_configs_.size() - look_back;)
    if (suite_configs_[k] == config) return static_cast<std::uint32_t>(k);
  suite_configs_.push_back(config);
  has_models_ = has_models_ || !suite.models().empty();
  models_concurrent_ = models_concurrent_ && suite.models_concurrent();
  suite_pool_.push_back(std::move(suite));
  return static_cast<std::uint32_t>(suite_pool_.size() - 1);
}

bool World::set_dense_slot(int id, std::int32_t s) {
  if (id < 0) return false;
  const auto i = static_cast<std::size_t>(id);
  if (i >= by_id_.size()) {
    // Only ids within a few times the robot count get a dense entry (memory stays
    // proportional to the robots); others go through the hash map alone.
    if (s < 0 || i >= 4 * robots_.size() + 4096) return false;
    by_id_.resize(std::max(i + 1, 2 * by_id_.size()));
  }
  by_id_[i].slot = s;
  return true;
}

void World::set_dense_added(int id, std::uint32_t added) {
  if (id >= 0 && static_cast<std::size_t>(id) < by_id_.size()) by_id_[static_cast<std::size_t>(id)].added = added;
}

std::size_t World::added_index(int id) const {
  if (id >= 0 && static_cast<std::size_t>(id) < by_id_.size()) {
    const IdEntry& e = by_id_[static_cast<std::size_t>(id)];
    if (e.slot >= 0) return e.added;
  }
  return added_of_slot_[slot(id)];
}

void World::refresh_max_radius() {
  max_radius_m_ = 0.0;
  min_radius_m_ = bodies_.empty() ? 0.0 : kNoHit;
  for (const Body& b : bodies_) {
    max_radius_m_ = std::max(max_radius_m_, b.radius_m);
    const BodyOutline* outline = outline_of(b);
    min_radius_m_ = std::min(min_radius_m_, outline ? outline_inner_radius_m(outline->local_m) : b.radius_m);
  }
}

void World::prefetch(int id) const {
  // Its readings, pose and wheel commands are in the agents' order (the CPU's own
  // prefetcher follows that): the id table's entry, found by id, is what to ask for.
  if (id >= 0 && static_cast<std::size_t>(id) < by_id_.size())
    __builtin_prefetch(&by_id_[static_cast<std::size_t>(id)]);
}

void World::set_wheel_speeds(int id, int left_units, int right_units) {
  commands_[added_index(id)] = {clamp_speed_units(left_units), clamp_speed_units(right_units)};
}

void World::set_observed_pose(int id, Pose2 pose, TimeUs t_us) {
  const std::size_t s = slot(id);
  RobotState& r = robots_[s];
  if (r.kind != RobotKind::kReal) throw std::invalid_argument(label(id) + ": set_observed_pose is for real robots");
  if (!finite(pose.position_m) || !std::isfinite(pose.heading_rad))
    throw std::invalid_argument(label(id) + ": observed pose is not finite");
  r.pose = {pose.position_m, wrap_rad_pi(pose.heading_rad)};
  r.pose_t_us = t_us;
  r.observed = true;
  poses_[added_of_slot_[s]] = r.pose;
  headings_[s] = {std::cos(r.pose.heading_rad), std::sin(r.pose.heading_rad)};
  changed();
  bodies_[s].position_m = bodies_[s].previous_m = pose.position_m;
  if (bodies_[s].outline >= 0) {
    BodyOutline& outline = outlines_[static_cast<std::size_t>(bodies_[s].outline)];
    outline.heading = outline.start_heading = headings_[s];
  }
  grid_.move(s, pose.position_m);
}

void World::set_odometer(int id, OdometryReading counters) {
  RobotState& r = robots_[slot(id)];
  r.left_wheel_travel_m = static_cast<double>(counters.left_pulses) * kKheperaPulse_m;
  r.right_wheel_travel_m = static_cast<double>(counters.right_pulses) * kKheperaPulse_m;
  changed();
}

int World::add_moving_obstacle(const MovingObstacleConfig& config) {
  const std::string what = "moving obstacle " + std::to_string(movers_.size());
  MovingObstacle mover(config, what);
  const double tol = config_.collision.tolerance_m;
  auto overlaps_segment = [&](Vec2 a, Vec2 b) {
    const Contact c = mover.shape() == MovingShape::kDisc
                          ? disc_segment_contact(mover.position_m(), mover.bounding_radius_m(), a, b)
                          : convex_polygon_segment_contact(mover.world_vertices_m(), a, b);
    return c.separation_m < -tol;
  };
  statics_.for_each_in_box(box_around(mover.position_m(), mover.bounding_radius_m()), [&](const IndexedSegment& seg) {
    if (overlaps_segment(seg.a_m, seg.b_m))
      throw std::invalid_argument(what + ": placed overlapping " + to_string(seg.owner));
  });
  if (const int inside = map_.obstacle_containing(mover.position_m()); inside >= 0)
    throw std::invalid_argument(what + ": placed inside obstacle " + std::to_string(inside));
  if (map_.field().boundary_walls) {
    const Vec2 p = mover.position_m();
    if (p.x < 0.0 || p.y < 0.0 || p.x > map_.field().width_m || p.y > map_.field().height_m)
      throw std::invalid_argument(what + ": placed outside the walled field");
  }
  for (std::size_t j = 0; j < bodies_.size(); ++j) {
    const Body& b = bodies_[j];
    OutlineBuffer buffer;
    const Contact c = shape_mover_contact(place_body(b.position_m, b.radius_m, outline_of(b), buffer), mover);
    if (c.separation_m < -tol) throw std::invalid_argument(what + ": placed overlapping " + label(ids_[j]));
  }
  movers_.push_back(std::move(mover));
  changed();
  return static_cast<int>(movers_.size() - 1);
}

double World::substep_limit_m() const {
  if (config_.max_substep_travel_m > 0.0) return config_.max_substep_travel_m;
  return min_radius_m_ > 0.0 ? min_radius_m_ : kKheperaRadius_m;
}

std::span<const CollisionEvent> World::step(TimeUs dt_us) {
  if (dt_us < 0) throw std::invalid_argument("world: step dt_us must be >= 0");
  if (dt_us == 0) return {};
  changed();
  using Clock = std::chrono::steady_clock;
  const Clock::time_point started = Clock::now();
  const bool reorder_due = config_.reorder_every_steps > 0 && ++steps_ % config_.reorder_every_steps == 0;
  if (renumber_due_ || reorder_due) renumber_by_place();
  double collisions_s = 0.0;
  const double dt_s = us_to_seconds(dt_us);

  // Wheel speeds for the whole step (commands are constant over a step), the counters,
  // and the longest distance anything travels (each robot on its own: threads may share
  // the robots, and the largest travel is the same whoever finds it).
  std::mutex max_mutex;
  double max_travel_m = 0.0;
  step_wheels_mps_.resize(robots_.size());
  auto wheels = [&](std::size_t begin, std::size_t end) {
    const double travel_m = start_wheels(begin, end, dt_s);
    std::lock_guard lock(max_mutex);
    max_travel_m = std::max(max_travel_m, travel_m);
  };
  if (drives_concurrent_) {
    for_robot_slots(wheels);
  } else {
    wheels(0, robots_.size());  // a drive model that may not run for two robots at once
  }
  for (const MovingObstacle& m : movers_) max_travel_m = std::max(max_travel_m, m.velocity_mps().norm() * dt_s);

  constexpr double kMaxSubsteps = 100000.0;
  const int substeps = static_cast<int>(std::clamp(std::ceil(max_travel_m / substep_limit_m()), 1.0, kMaxSubsteps));
  const double h_s = dt_s / substeps;
  if (substeps > 1) {
    for_robot_slots([&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        const RobotState& r = robots_[i];
        if (r.kind == RobotKind::kVirtual) set_arc(i, step_wheels_mps_[i], r.wheel_base_m, h_s, substeps);
      }
    });
  }

  CollisionScene cs{bodies_, ids_, grid_, statics_, movers_, max_radius_m_, id_order_, outlines_};
  resolver_.begin_step();
  const TimeUs end_t_us = t_us_ + dt_us;
  for (int k = 0; k < substeps; ++k) {
    for (MovingObstacle& m : movers_) {
      m.begin_substep();
      m.translate(m.velocity_mps() * h_s);
    }
    const bool last = k + 1 == substeps;
    if (substeps == 1) {
      for_robot_slots([&](std::size_t begin, std::size_t end) { move_whole_step(begin, end, dt_s, end_t_us); });
    } else {
      for_robot_slots([&](std::size_t begin, std::size_t end) { move_substep(begin, end, last, end_t_us); });
    }
    if (!outline_slots_.empty()) turn_outlines(substeps);
    const Clock::time_point resolving = Clock::now();
    resolver_.resolve(cs, t_us_ + dt_us * (k + 1) / substeps);
    if (!outline_slots_.empty()) follow_turned_back_outlines(substeps);
    collisions_s += std::chrono::duration<double>(Clock::now() - resolving).count();
  }
  if (!turned_back_.empty()) finish_turned_back(substeps);
  for (const int pushed : resolver_.pushed()) {
    const auto i = static_cast<std::size_t>(pushed);
    if (robots_[i].kind != RobotKind::kVirtual) continue;  // (the resolver pushes none: they are not pushable)
    robots_[i].pose.position_m = bodies_[i].position_m;
    poses_[added_of_slot_[i]].position_m = bodies_[i].position_m;
  }
  t_us_ = end_t_us;
  step_times_.collisions_s += collisions_s;
  step_times_.integration_s += std::chrono::duration<double>(Clock::now() - started).count() - collisions_s;
  return resolver_.end_step();
}

double World::start_wheels(std::size_t begin, std::size_t end, double dt_s) {
  double max_travel_m = 0.0;
  for (std::size_t i = begin; i < end; ++i) {
    RobotState& r = robots_[i];
    if (r.kind != RobotKind::kVirtual) continue;
    // In added order, where the agents wrote: a small table, but not in cache at 100,000
    // robots once the step's passes went through memory, so asked for a few robots ahead.
    if (i + kStorePrefetch < end) __builtin_prefetch(&commands_[added_of_slot_[i + kStorePrefetch]]);
    const WheelUnits command = commands_[added_of_slot_[i]];
    const double left_cmd = speed_units_to_mps(command.left);
    const double right_cmd = speed_units_to_mps(command.right);
    if (DriveModel* drive = drives_[added_of_slot_[i]].get()) {
      NoiseRng rng = NoiseRng::keyed(config_.noise_seed, r.id, t_us_, NoisePurpose::kWheels);
      const DriveOutput out =
          drive->drive({t_us_, r.id, r.pose, dt_s, command.left, command.right, {left_cmd, right_cmd}, rng});
      r.left_wheel_travel_m += out.counted_mps.x * dt_s;
      r.right_wheel_travel_m += out.counted_mps.y * dt_s;
      max_travel_m = std::max(max_travel_m, std::abs(0.5 * (out.ground_mps.x + out.ground_mps.y)) * dt_s);
      step_wheels_mps_[i] = out.ground_mps;
      continue;
    }
    double left_gain = 1.0 + r.noise.left_bias, right_gain = 1.0 + r.noise.right_bias;
    if (r.noise.slip_sd > 0.0) {
      NoiseRng rng = NoiseRng::keyed(config_.noise_seed, r.id, t_us_, NoisePurpose::kWheels);
      left_gain += r.noise.slip_sd * fast_normal(rng);
      right_gain += r.noise.slip_sd * fast_normal(rng);
    }
    const double left_mps = left_cmd * left_gain, right_mps = right_cmd * right_gain;
    if (r.noise.odometer_counts_slip) {
      r.left_wheel_travel_m += left_mps * dt_s;
      r.right_wheel_travel_m += right_mps * dt_s;
    } else {
      r.left_wheel_travel_m += left_cmd * dt_s;
      r.right_wheel_travel_m += right_cmd * dt_s;
    }
    max_travel_m = std::max(max_travel_m, std::abs(0.5 * (left_mps + right_mps)) * dt_s);
    step_wheels_mps_[i] = {left_mps, right_mps};
  }
  return max_travel_m;
}

void World::move_substep(std::size_t begin, std::size_t end, bool last, TimeUs end_t_us) {
  for (std::size_t i = begin; i < end; ++i) {
    Body& b = bodies_[i];
    b.previous_m = b.position_m;
    if (!b.pushable) continue;  // a real robot: only the camera moves it
    Motion& m = motion_[i];
    const Vec2 d = m.local_step_m;
    b.position_m = b.position_m + Vec2{m.heading.x * d.x - m.heading.y * d.y, m.heading.y * d.x + m.heading.x * d.y};
    m.heading = {m.heading.x * m.cos_turn - m.heading.y * m.sin_turn,
                 m.heading.y * m.cos_turn + m.heading.x * m.sin_turn};
    // The step's end pose at once, while the records are in cache (a pass of its own
    // read them from memory again at 100,000 robots); the few robots the collisions
    // step() resolves after the move are set again after them.
    if (last) finish_move(i, end, end_t_us, m.heading, m.end_heading_rad);
  }
}

void World::move_whole_step(std::size_t begin, std::size_t end, double dt_s, TimeUs end_t_us) {
  // The same arithmetic as set_arc and one substep of step()'s loop, on the same values:
  // the same poses to the bit, with the arc made here rather than stored in motion_ by
  // one pass and read back by the next (at 100,000 robots, 110 bytes a robot less
  // through memory each step).
  for (std::size_t i = begin; i < end; ++i) {
    Body& b = bodies_[i];
    b.previous_m = b.position_m;
    if (!b.pushable) continue;  // a real robot: only the camera moves it
    const RobotState& r = robots_[i];
    const Vec2 wheels_mps = step_wheels_mps_[i];
    const ArcStep arc = diff_drive_arc(wheels_mps.x, wheels_mps.y, r.wheel_base_m, dt_s);
    const Vec2 d = arc.local_displacement_m;
    const Vec2 h = headings_[i];
    b.position_m = b.position_m + Vec2{h.x * d.x - h.y * d.y, h.y * d.x + h.x * d.y};
    const Vec2 turned{h.x * arc.cos_heading_change - h.y * arc.sin_heading_change,
                      h.y * arc.cos_heading_change + h.x * arc.sin_heading_change};
    finish_move(i, end, end_t_us, turned, r.pose.heading_rad + arc.heading_change_rad);
  }
}

void World::set_arc(std::size_t i, Vec2 wheels_mps, double wheel_base_m, double h_s, int substeps) {
  Motion& m = motion_[i];
  const ArcStep arc = diff_drive_arc(wheels_mps.x, wheels_mps.y, wheel_base_m, h_s);
  m.local_step_m = arc.local_displacement_m;
  m.cos_turn = arc.cos_heading_change;
  m.sin_turn = arc.sin_heading_change;
  m.heading = headings_[i];  // cos and sin of robots_[i].pose.heading_rad
  m.end_heading_rad = robots_[i].pose.heading_rad + arc.heading_change_rad * substeps;
}

void World::finish_move(std::size_t i, std::size_t end, TimeUs end_t_us, Vec2 heading, double end_heading_rad) {
  RobotState& r = robots_[i];
  r.pose = {bodies_[i].position_m, wrap_rad_pi(end_heading_rad)};
  r.pose_t_us = end_t_us;
  // poses_ is in added order, far from this slot's: ask for the one a few robots on.
  // (A pose is 24 bytes: a quarter of them straddle two lines, so both ends are asked for.)
  if (i + kStorePrefetch < end) {
    const Pose2* ahead = &poses_[added_of_slot_[i + kStorePrefetch]];
    __builtin_prefetch(ahead, 1);
    __builtin_prefetch(reinterpret_cast<const char*>(ahead + 1) - 1, 1);
  }
  poses_[added_of_slot_[i]] = r.pose;
  // The substeps rotated the heading vector as far as the heading turned: no sine and
  // cosine per robot (they were a twentieth of a step). One Newton step on 1/|h| keeps it
  // of unit length (rotations are exact to a few ulps; this stops the drift).
  const Vec2 h = heading;
  const double rescale = 1.5 - 0.5 * (h.x * h.x + h.y * h.y);
  headings_[i] = {h.x * rescale, h.y * rescale};
}

SensorReadings World::sense(int id, TimeUs t_us) const {
  SensorReadings out;
  sense_into(id, t_us, out);
  return out;
}

SensorReadings World::sense(int id, TimeUs t_us, NoiseRng& rng) const {
  const std::size_t s = slot(id);
  const RobotState& r = robots_[s];
  std::optional<OdometryReading> odometry;
  if (r.kind == RobotKind::kVirtual) odometry = r.odometer();
  SensorReadings out;
  refresh_mobiles();
  suite_pool_[suite_of_[s]].sense(scene(), static_cast<int>(s), r.pose, headings_[s], odometry, t_us, rng, out, r.id,
                                  collect_marks_);
  return out;
}

void World::sense_into(int id, TimeUs t_us, SensorReadings& out) const {
  if (ahead_valid_ && ahead_t_us_ == t_us) {
    const std::size_t added = added_index(id);
    const StoredReadings& stored = ahead_[added];
    out.t_us = stored.t_us;
    if (stored.has_proximity)
      out.proximity = stored.proximity;
    else
      out.proximity.reset();
    if (stored.has_odometry)
      out.odometry = stored.odometry;
    else
      out.odometry.reset();
    if (stored.has_lists) {
      const StoredLists& lists = ahead_lists_[added];
      out.ranges = lists.ranges, out.beacons = lists.beacons, out.track = lists.track, out.models = lists.models;
      out.marks = lists.marks;
    } else {
      out.ranges.clear(), out.beacons.clear(), out.track.clear(), out.models.clear(), out.marks.clear();
    }
    return;
  }
  refresh_mobiles();
  sense_slot(scene(), slot(id), t_us, out);
}

void World::store_readings(std::size_t added, SensorReadings& readings) {
  StoredReadings& stored = ahead_[added];
  stored.t_us = readings.t_us;
  stored.has_proximity = readings.proximity.has_value();
  if (stored.has_proximity) stored.proximity = *readings.proximity;
  stored.has_odometry = readings.odometry.has_value();
  if (stored.has_odometry) stored.odometry = *readings.odometry;
  stored.has_lists = !readings.ranges.empty() || !readings.beacons.empty() || !readings.track.empty() ||
                     !readings.models.empty() || !readings.marks.empty();
  if (stored.has_lists) {
    // Swapped, not copied: the record's old lists become the scratch's, capacity kept.
    StoredLists& lists = ahead_lists_[added];
    lists.ranges.swap(readings.ranges), lists.beacons.swap(readings.beacons), lists.track.swap(readings.track);
    lists.models.swap(readings.models), lists.marks.swap(readings.marks);
  }
}

void World::sense_ahead(TimeUs t_us) {
  if (ahead_valid_ && ahead_t_us_ == t_us) return;
  ahead_.resize(robots_.size());  // by index in added_order_
  const bool lists =
      std::any_of(suite_pool_.begin(), suite_pool_.end(), [](const SensorSuite& x) { return x.has_lists(); });
  ahead_lists_.resize(lists ? robots_.size() : 0);
  refresh_mobiles();
  const Scene sc = scene();
  // Slot order is by place (renumber_by_place): a robot's neighbours were just read. A
  // sensor model that may not sense for two robots at once keeps the sweep on one thread.
  auto sweep = [&](std::size_t begin, std::size_t end) {
    SensorReadings readings;  // this thread's, reused (its lists keep their capacity)
    for (std::size_t s = begin; s < end; ++s) {
      // The store is in the agents' order, so each robot's record is far from the last
      // one's: ask for it (for writing) a few robots ahead. A hint; GCC and Clang on any CPU.
      if (s + kStorePrefetch < end) {
        __builtin_prefetch(&ahead_[added_of_slot_[s + kStorePrefetch]], 1);
        grid_.prefetch_around(s + kStorePrefetch);
      }
      sense_slot(sc, s, t_us, readings);
      store_readings(added_of_slot_[s], readings);
    }
  };
  if (models_concurrent_) {
    for_robot_slots(sweep);
  } else {
    sweep(0, robots_.size());
  }
  ahead_t_us_ = t_us;
  ahead_valid_ = true;
}

template <class T>
void World::permute(std::vector<T>& items, std::vector<T>& scratch) {
  // Into a kept buffer (no allocation, no page faults after the first time), each thread
  // writing its own stretch of new slots.
  scratch.resize(items.size());
  for_robot_slots([&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) scratch[k] = std::move(items[new_order_[k]]);
  });
  items.swap(scratch);
}

void World::renumber_by_place() {
  const std::size_t n = robots_.size();
  // By cell, in the grid's numbering (blocks of 8 x 8 cells, row by row), and by id
  // within a cell (so that the order does not depend on the previous one).
  const GridGeometry& g = grid_geometry_;
  std::vector<RenumberKey>& keys = renumber_keys_;
  keys.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    keys[i] = {static_cast<std::uint64_t>(g.cell_of(bodies_[i].position_m)), ids_[i], static_cast<std::uint32_t>(i)};
  }
  std::sort(keys.begin(), keys.end(), [](const RenumberKey& a, const RenumberKey& b) {
    return a.place != b.place ? a.place < b.place : a.id < b.id;
  });
  new_order_.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    new_order_[k] = keys[k].slot;
    keys[k].slot = static_cast<std::uint32_t>(k);  // from now on: its new slot
  }
  permute(robots_, robots_scratch_), permute(bodies_, bodies_scratch_), permute(ids_, ints_scratch_);
  permute(suite_of_, slots_scratch_), permute(added_of_slot_, slots_scratch_), permute(headings_, headings_scratch_);
  // motion_ is the step's scratch, filled after this.
  for (std::size_t k = 0; k < n; ++k) {
    // The hash map only for ids without a dense entry: at 100,000 robots a map write
    // per robot was a cache miss each.
    if (!set_dense_slot(ids_[k], static_cast<std::int32_t>(k))) slot_of_[ids_[k]] = k;
  }
  grid_.rebuild(n, [&](std::size_t i) { return bodies_[i].position_m; });
  refresh_outline_slots();
  // The collision resolver's order: by id, whatever the slots.
  std::sort(keys.begin(), keys.end(), [](const RenumberKey& a, const RenumberKey& b) { return a.id < b.id; });
  id_order_.resize(n);
  for (std::size_t k = 0; k < n; ++k) id_order_[k] = keys[k].slot;
  renumber_due_ = false;
  changed();
}

void World::sense_slot(const Scene& scene, std::size_t s, TimeUs t_us, SensorReadings& out) const {
  const RobotState& r = robots_[s];
  std::optional<OdometryReading> odometry;
  if (r.kind == RobotKind::kVirtual) odometry = r.odometer();
  NoiseRng rng = NoiseRng::keyed(config_.noise_seed, r.id, t_us, NoisePurpose::kSensing);
  suite_pool_[suite_of_[s]].sense(scene, static_cast<int>(s), r.pose, headings_[s], odometry, t_us, rng, out, r.id,
                                  collect_marks_);
}

void World::sense_all(TimeUs t_us, std::vector<SensorReadings>& out) const {
  out.resize(robots_.size());
  refresh_mobiles();
  const Scene sc = scene();
  for (std::size_t s = 0; s < robots_.size(); ++s) sense_slot(sc, s, t_us, out[s]);
}

WorldSnapshot World::snapshot() const {
  WorldSnapshot snap;
  snap.t_us = t_us_;
  snap.robots.reserve(robots_.size());
  for (std::size_t k = 0; k < added_order_.size(); ++k) {
    const RobotState& r = robot(added_order_[k]);
    snap.robots.push_back({r.id, r.kind, r.pose, r.radius_m, commands_[k].left, commands_[k].right, {}});
    if (const BodyOutline* outline = outline_of(bodies_[slot(r.id)])) snap.robots.back().outline_m = outline->local_m;
  }
  for (const MovingObstacle& m : movers_)
    snap.moving_obstacles.push_back(
        {m.shape(), m.position_m(), m.velocity_mps(), m.bounding_radius_m(), m.world_vertices_m()});
  const auto events = resolver_.events();
  snap.collisions.assign(events.begin(), events.end());
  return snap;
}

double World::max_overlap_m() const {
  std::mutex worst_mutex;
  double worst_of_all = 0.0;
  auto check = [&](std::size_t begin, std::size_t end) {
    double worst = 0.0;
    for (std::size_t i = begin; i < end; ++i) worst = std::max(worst, overlap_of(i));
    std::lock_guard lock(worst_mutex);
    worst_of_all = std::max(worst_of_all, worst);
  };
  if (workers_ && workers_->threads() > 1 && bodies_.size() > 1)
    workers_->for_chunks(bodies_.size(), check);
  else
    check(0, bodies_.size());
  return worst_of_all;
}

double World::overlap_of(std::size_t i) const {
  double worst = 0.0;
  const Body& b = bodies_[i];
  if (!b.pushable) return worst;
  OutlineBuffer buffer;
  const BodyShape shape = place_body(b.position_m, b.radius_m, outline_of(b), buffer);
  grid_.for_each_in_box(box_around(b.position_m, b.radius_m + max_radius_m_), [&](int jj) {
    const auto j = static_cast<std::size_t>(jj);
    if (j == i) return;
    const Body& other = bodies_[j];
    double gap = std::sqrt(distance_sq(b.position_m, other.position_m)) - b.radius_m - other.radius_m;
    if (gap < 0.0 && (b.outline >= 0 || other.outline >= 0)) {
      OutlineBuffer other_buffer;
      gap = shape_shape_contact(shape, place_body(other.position_m, other.radius_m, outline_of(other), other_buffer))
                .separation_m;
    }
    worst = std::max(worst, -gap);
  });
  statics_.for_each_in_box(box_around(b.position_m, b.radius_m), [&](const IndexedSegment& seg) {
    worst = std::max(worst, -shape_segment_contact(shape, seg.a_m, seg.b_m).separation_m);
  });
  if (map_.obstacle_containing(b.position_m) >= 0) worst = std::max(worst, b.radius_m);
  for (const MovingObstacle& m : movers_) worst = std::max(worst, -shape_mover_contact(shape, m).separation_m);
  return worst;
}

}  // namespace rilbed::environment
