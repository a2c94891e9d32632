#include "agents/library_sensor_models.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <set>
#include <stdexcept>

#include "environment/random.hpp"
#include "environment/scene.hpp"

namespace rilbed::agents {

namespace {

constexpr std::uint32_t kMaxParams = 64;
constexpr std::uint32_t kMaxValues = 64;
constexpr std::uint32_t kMarksPerCall = 32;  // room a model gets to draw, per robot and call

std::int32_t scene_on_track(const void* scene, double x_m, double y_m) {
  return static_cast<const environment::Scene*>(scene)->on_track({x_m, y_m}) ? 1 : 0;
}
double rng_normal(void* rng) { return environment::fast_normal(*static_cast<environment::NoiseRng*>(rng)); }
double rng_uniform(void* rng) { return environment::uniform01(*static_cast<environment::NoiseRng*>(rng)); }

// One mounted model: the library's instance, called through its functions.
class LibrarySensorModel final : public environment::SensorModel {
 public:
  LibrarySensorModel(const SensorModelEntry& entry, void* instance, std::string name, std::string who)
      : library_(entry.library),
        model_(*entry.model),
        instance_(instance),
        name_(std::move(name)),
        who_(std::move(who)),
        value_count_(entry.value_count),
        provides_track_(entry.provides_track),
        concurrent_(entry.concurrent) {}
  ~LibrarySensorModel() override { model_.destroy(instance_); }
  LibrarySensorModel(const LibrarySensorModel&) = delete;
  LibrarySensorModel& operator=(const LibrarySensorModel&) = delete;

  const std::string& name() const override { return name_; }
  std::size_t value_count() const override { return value_count_; }
  bool provides_track() const override { return provides_track_; }
  bool concurrent() const override { return concurrent_; }

  void sense(const environment::SensorModelCall& c, std::span<double> values) const override {
    std::uint32_t mark_count = 0;
    rilbed_mark marks[kMarksPerCall];
    const rilbed_sense_call call{c.t_us,
                                 c.robot_id,
                                 c.pose.position_m.x,
                                 c.pose.position_m.y,
                                 c.pose.heading_rad,
                                 c.heading.x,
                                 c.heading.y,
                                 c.mobiles.data(),
                                 static_cast<std::uint32_t>(c.mobiles.size()),
                                 &c.scene,
                                 &scene_on_track,
                                 &c.rng,
                                 &rng_normal,
                                 &rng_uniform,
                                 c.marks ? marks : nullptr,
                                 c.marks ? kMarksPerCall : 0u,
                                 &mark_count};
    std::fill(values.begin(), values.end(), 0.0);
    char error[512] = {0};
    if (model_.sense(instance_, &call, values.data(), error, sizeof error) != 0) {
      error[sizeof error - 1] = '\0';
      throw std::runtime_error(who_ + " of robot " + std::to_string(c.robot_id) + ": its reading at t = " +
                               std::to_string(c.t_us / 1000) + " ms failed: " + (error[0] ? error : "(no message)"));
    }
    if (c.marks) keep_marks(marks, std::min(mark_count, kMarksPerCall), *c.marks);
    for (double& v : values) {
      if (!std::isfinite(v)) {
        throw std::runtime_error(who_ + " of robot " + std::to_string(c.robot_id) + ": its reading at t = " +
                                 std::to_string(c.t_us / 1000) + " ms is not a finite number");
      }
    }
  }

 private:
  // The marks a call drew that a display can draw: known shapes, finite, within 100 m of
  // the robot (anything else is dropped, not an error: marks are for the eye only).
  static void keep_marks(const rilbed_mark* marks, std::uint32_t count, std::vector<environment::SensorMark>& out) {
    for (std::uint32_t i = 0; i < count; ++i) {
      const rilbed_mark& m = marks[i];
      const bool circle = m.shape == RILBED_MARK_CIRCLE, line = m.shape == RILBED_MARK_LINE;
      auto near = [](double v) { return std::isfinite(v) && std::abs(v) <= 100.0; };
      if (!(circle || line) || !near(m.x_m) || !near(m.y_m)) continue;
      if (circle && !(near(m.radius_m) && m.radius_m > 0.0)) continue;
      if (line && !(near(m.x2_m) && near(m.y2_m))) continue;
      out.push_back({circle ? environment::SensorMark::Shape::kCircle : environment::SensorMark::Shape::kLine,
                     {m.x_m, m.y_m},
                     {line ? m.x2_m : 0.0, line ? m.y2_m : 0.0},
                     circle ? m.radius_m : 0.0,
                     m.rgba});
    }
  }

  std::shared_ptr<const PluginLibrary> library_;
  const rilbed_sensor_model& model_;
  void* instance_;
  std::string name_;
  std::string who_;
  std::size_t value_count_;
  bool provides_track_;
  bool concurrent_;
};

}  // namespace

core::Result<std::string> model_text(const char* text, const std::string& what, std::size_t limit) {
  if (!text) return core::Failure{what + " is NULL"};
  const std::size_t n = strnlen(text, limit + 1);
  if (n > limit) return core::Failure{what + " is longer than " + std::to_string(limit) + " bytes"};
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    // ASCII only: keys, units and summaries go to terminals, JSON and messages as they are.
    if (c < 0x20 || c > 0x7e) return core::Failure{what + " holds a byte that is not printable ASCII"};
  }
  return std::string(text, n);
}

core::Result<std::string> model_name(const char* text, const std::string& what) {
  core::Result<std::string> name = model_text(text, what, 128);
  if (!name) return name;
  if (name->empty() || name->find_first_of(" ,:{}[]#\"'") != std::string::npos)
    return core::Failure{what + " '" + *name + "' is empty or holds a space or YAML punctuation"};
  return name;
}

core::Result<ModelHeader> model_header(std::uint32_t abi_version, const char* name, const char* summary,
                                       const std::string& what) {
  if (abi_version != RILBED_ABI_VERSION) {
    return core::Failure{what + " was built against rilbed's SDK ABI version " + std::to_string(abi_version) +
                         ", this rilbed loads version " + std::to_string(RILBED_ABI_VERSION)};
  }
  core::Result<std::string> checked_name = model_name(name, what + " name");
  if (!checked_name) return core::Failure{checked_name.error()};
  const std::string who = what + " '" + *checked_name + "'";
  core::Result<std::string> checked_summary = model_text(summary, who + " summary");
  if (!checked_summary) return core::Failure{checked_summary.error()};
  return ModelHeader{*checked_name, *checked_summary, who};
}

core::Result<SensorParamSpec> model_param_spec(const rilbed_sensor_param& p, const std::string& what) {
  core::Result<std::string> key = model_text(p.key, what + " key", 64);
  if (!key) return core::Failure{key.error()};
  if (sensor_param_key(*key).empty()) return core::Failure{what + " key is empty"};
  const std::string who = what + " '" + *key + "'";
  core::Result<std::string> unit = model_text(p.unit, who + " unit", 32);
  core::Result<std::string> summary = model_text(p.summary, who + " summary");
  if (!unit) return core::Failure{unit.error()};
  if (!summary) return core::Failure{summary.error()};
  if (std::isnan(p.min) || std::isnan(p.max) || !(p.min <= p.max)) return core::Failure{who + " has no usable range"};
  SensorParamSpec spec{*key, *unit, *summary, std::nullopt, p.integer != 0, p.min, p.max};
  if (p.has_default) {
    if (!std::isfinite(p.default_value) || p.default_value < p.min || p.default_value > p.max)
      return core::Failure{who + " has a default that is not a finite number in its range"};
    if (spec.integer && p.default_value != std::floor(p.default_value))
      return core::Failure{who + " is whole but its default is not"};
    spec.default_value = p.default_value;
  }
  return spec;
}

StaticWorldView::StaticWorldView(const environment::StaticMap& map) {
  const environment::FieldConfig& f = map.field();
  if (f.boundary_walls) {
    const double w = f.width_m, h = f.height_m;
    segments = {{0, 0, w, 0}, {w, 0, w, h}, {w, h, 0, h}, {0, h, 0, 0}};
  }
  for (const environment::ObstacleConfig& o : map.obstacles()) {
    for (std::size_t i = 0, n = o.vertices_m.size(); i < n; ++i) {
      const Vec2 a = o.vertices_m[i], b = o.vertices_m[(i + 1) % n];
      segments.push_back({a.x, a.y, b.x, b.y});
    }
  }
  for (const environment::TrackConfig& t : map.tracks()) {
    const std::size_t n = t.points_m.size();
    for (std::size_t i = 0; i + 1 < n + (t.closed ? 1 : 0); ++i) {
      const Vec2 a = t.points_m[i], b = t.points_m[(i + 1) % n];
      tracks.push_back({a.x, a.y, b.x, b.y, 0.5 * t.width_m});
    }
  }
  raw = {f.width_m,       f.height_m,
         segments.data(), static_cast<std::uint32_t>(segments.size()),
         tracks.data(),   static_cast<std::uint32_t>(tracks.size())};
}

core::Result<std::vector<SensorParamSpec>> model_param_specs(const rilbed_sensor_param* params, std::uint32_t count,
                                                             const std::string& who) {
  if (count > kMaxParams) return core::Failure{who + " has more than 64 parameters"};
  if (count > 0 && !params) return core::Failure{who + " has parameters but their list is NULL"};
  std::vector<SensorParamSpec> specs;
  std::set<std::string> keys;
  for (std::uint32_t i = 0; i < count; ++i) {
    core::Result<SensorParamSpec> p = model_param_spec(params[i], who + " parameter " + std::to_string(i));
    if (!p) return core::Failure{p.error()};
    if (!keys.insert(sensor_param_key(p->key)).second)
      return core::Failure{who + " names parameter '" + p->key + "' twice"};
    specs.push_back(*p);
  }
  return specs;
}

std::string sensor_param_key(std::string_view key) {
  std::string out;
  bool gap = false;
  for (const char c : key) {
    if (c == ' ' || c == '_' || c == '-' || c == '\t') {
      gap = !out.empty();
      continue;
    }
    if (gap) out.push_back('_');
    gap = false;
    out.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  }
  return out;
}

const SensorParamSpec* SensorModelEntry::param(std::string_view key) const {
  const std::string wanted = sensor_param_key(key);
  for (const SensorParamSpec& p : params) {
    if (sensor_param_key(p.key) == wanted) return &p;
  }
  return nullptr;
}

core::Result<SensorModelEntry> sensor_model_entry(const rilbed_sensor_model& m,
                                                  std::shared_ptr<const PluginLibrary> library,
                                                  const std::string& origin) {
  core::Result<ModelHeader> header = model_header(m.abi_version, m.name, m.summary, origin + ": sensor model");
  if (!header) return core::Failure{header.error()};
  const std::string& who = header->who;
  if (!m.create || !m.sense || !m.destroy) return core::Failure{who + " lacks its create, sense or destroy function"};
  if (m.value_count < 1 || m.value_count > kMaxValues) return core::Failure{who + " must write 1 to 64 values"};
  SensorModelEntry e;
  e.name = header->name;
  e.summary = header->summary;
  e.origin = origin;
  e.value_count = m.value_count;
  e.concurrent = m.concurrent != 0;
  e.library = std::move(library);
  e.model = &m;
  if (m.provides) {
    core::Result<std::string> provides = model_text(m.provides, who + " provides", 32);
    if (!provides) return core::Failure{provides.error()};
    if (*provides != "track") return core::Failure{who + " provides '" + *provides + "': only \"track\" or NULL"};
    e.provides_track = true;
  }
  core::Result<std::vector<SensorParamSpec>> params = model_param_specs(m.params, m.param_count, who);
  if (!params) return core::Failure{params.error()};
  e.params = std::move(*params);
  return e;
}

core::Result<std::vector<SensorModelEntry>> load_library_sensor_models(const std::filesystem::path& path) {
  return load_model_list<SensorModelEntry, rilbed_sensor_model>(path, "rilbed_sensor_models", "sensor model",
                                                                &sensor_model_entry);
}

core::Result<std::shared_ptr<const environment::SensorModel>> mount_sensor_model(const SensorModelEntry& entry,
                                                                                 const SensorMount& mount,
                                                                                 const environment::StaticMap& map,
                                                                                 TimeUs quantum_us) {
  const std::string who = "sensor model " + entry.name + " (" + entry.origin + ")";
  if (mount.param_values.size() != entry.params.size()) {
    return core::Failure{who + ": " + std::to_string(mount.param_values.size()) + " parameter values for " +
                         std::to_string(entry.params.size()) + " parameters"};
  }
  const StaticWorldView world(map);
  const rilbed_sensor_setup setup{static_cast<std::uint32_t>(mount.param_values.size()),
                                  mount.param_values.data(),
                                  mount.mount_x_m,
                                  mount.mount_y_m,
                                  mount.mount_yaw_deg,
                                  quantum_us,
                                  &world.raw,
                                  mount.parameter_file.c_str()};
  char error[512] = {0};
  void* instance = entry.model->create(&setup, error, sizeof error);
  error[sizeof error - 1] = '\0';
  if (!instance) {
    return core::Failure{who + " with " + (mount.parameter_file.empty() ? "its defaults" : mount.parameter_file) +
                         ": cannot be made: " + (error[0] ? error : "(no message)")};
  }
  const std::string name = mount.name.empty() ? entry.name : mount.name;
  return std::shared_ptr<const environment::SensorModel>(
      std::make_shared<LibrarySensorModel>(entry, instance, name, "sensor model " + name + " (" + entry.origin + ")"));
}

}  // namespace rilbed::agents
