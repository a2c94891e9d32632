#include "agents/library_actuator_models.hpp"

#include <cmath>
#include <cstring>
#include <stdexcept>

namespace rilbed::agents {

namespace {

double rng_normal(void* rng) { return environment::fast_normal(*static_cast<environment::NoiseRng*>(rng)); }
double rng_uniform(void* rng) { return environment::uniform01(*static_cast<environment::NoiseRng*>(rng)); }

// One robot's drive: its instance of the model.
class LibraryDrive final : public environment::DriveModel {
 public:
  LibraryDrive(std::shared_ptr<const PluginLibrary> library, const rilbed_actuator_model& model, void* instance,
               std::string who)
      : library_(std::move(library)), model_(model), instance_(instance), who_(std::move(who)) {}
  ~LibraryDrive() override { model_.destroy(instance_); }
  LibraryDrive(const LibraryDrive&) = delete;
  LibraryDrive& operator=(const LibraryDrive&) = delete;

  environment::DriveOutput drive(const environment::DriveCall& c) override {
    const rilbed_drive_call call{c.t_us, c.robot_id,   c.pose.position_m.x, c.pose.position_m.y, c.pose.heading_rad,
                                 c.dt_s, c.left_units, c.right_units,       c.command_mps.x,     c.command_mps.y,
                                 &c.rng, &rng_normal,  &rng_uniform};
    rilbed_drive_output out{c.command_mps.x, c.command_mps.y, c.command_mps.x, c.command_mps.y};
    char error[512] = {0};
    if (model_.drive(instance_, &call, &out, error, sizeof error) != 0) {
      error[sizeof error - 1] = '\0';
      throw std::runtime_error(who_ + ": its step at t = " + std::to_string(c.t_us / 1000) +
                               " ms failed: " + (error[0] ? error : "(no message)"));
    }
    for (const double v : {out.left_mps, out.right_mps, out.left_counted_mps, out.right_counted_mps}) {
      // A speed no Khepera-sized robot reaches, or not a number, is the model's mistake.
      if (!std::isfinite(v) || std::abs(v) > 100.0) {
        throw std::runtime_error(who_ + ": its step at t = " + std::to_string(c.t_us / 1000) +
                                 " ms gave a wheel speed that is not a finite number within 100 m/s");
      }
    }
    return {{out.left_mps, out.right_mps}, {out.left_counted_mps, out.right_counted_mps}};
  }

 private:
  std::shared_ptr<const PluginLibrary> library_;
  const rilbed_actuator_model& model_;
  void* instance_;
  std::string who_;
};

class LibraryDriveFactory final : public environment::DriveModelFactory {
 public:
  LibraryDriveFactory(const ActuatorModelEntry& entry, std::vector<double> values, const environment::StaticMap& map,
                      TimeUs step_us, std::string parameter_file)
      : library_(entry.library),
        model_(*entry.model),
        name_(entry.name),
        origin_(entry.origin),
        concurrent_(entry.concurrent),
        values_(std::move(values)),
        world_(std::make_unique<StaticWorldView>(map)),
        step_us_(step_us),
        parameter_file_(std::move(parameter_file)) {}

  std::unique_ptr<environment::DriveModel> make(int robot_id, double wheel_base_m) const override {
    const rilbed_actuator_setup setup{robot_id,
                                      static_cast<std::uint32_t>(values_.size()),
                                      values_.data(),
                                      wheel_base_m,
                                      step_us_,
                                      &world_->raw,
                                      parameter_file_.c_str()};
    char error[512] = {0};
    void* instance = model_.create(&setup, error, sizeof error);
    error[sizeof error - 1] = '\0';
    const std::string who = "actuator model " + name_ + " (" + origin_ + ") of robot " + std::to_string(robot_id);
    if (!instance) throw std::invalid_argument(who + ": cannot be made: " + (error[0] ? error : "(no message)"));
    return std::make_unique<LibraryDrive>(library_, model_, instance, who);
  }
  bool concurrent() const override { return concurrent_; }

 private:
  std::shared_ptr<const PluginLibrary> library_;
  const rilbed_actuator_model& model_;
  std::string name_;
  std::string origin_;
  bool concurrent_;
  std::vector<double> values_;
  std::unique_ptr<StaticWorldView> world_;
  TimeUs step_us_;
  std::string parameter_file_;
};

}  // namespace

core::Result<ActuatorModelEntry> actuator_model_entry(const rilbed_actuator_model& m,
                                                      std::shared_ptr<const PluginLibrary> library,
                                                      const std::string& origin) {
  core::Result<ModelHeader> header = model_header(m.abi_version, m.name, m.summary, origin + ": actuator model");
  if (!header) return core::Failure{header.error()};
  const std::string& who = header->who;
  if (!m.create || !m.drive || !m.destroy) return core::Failure{who + " lacks its create, drive or destroy function"};
  core::Result<std::vector<SensorParamSpec>> params = model_param_specs(m.params, m.param_count, who);
  if (!params) return core::Failure{params.error()};
  return ActuatorModelEntry{header->name,      header->summary,    origin, std::move(*params),
                            m.concurrent != 0, std::move(library), &m};
}

core::Result<std::vector<ActuatorModelEntry>> load_library_actuator_models(const std::filesystem::path& path) {
  return load_model_list<ActuatorModelEntry, rilbed_actuator_model>(path, "rilbed_actuator_models", "actuator model",
                                                                    &actuator_model_entry);
}

std::shared_ptr<const environment::DriveModelFactory> actuator_factory(const ActuatorModelEntry& entry,
                                                                       std::vector<double> param_values,
                                                                       const environment::StaticMap& map,
                                                                       TimeUs step_us, std::string parameter_file) {
  return std::make_shared<LibraryDriveFactory>(entry, std::move(param_values), map, step_us, std::move(parameter_file));
}

}  // namespace rilbed::agents
