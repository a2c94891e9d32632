#include "run/control_model.hpp"

#include <cmath>
#include <sstream>

#include "vision/vision_settings.hpp"

namespace rilbed::run {

void ControlModel::apply(const ControlAction& a) {
  switch (a.kind) {
    case ControlAction::Kind::kPause:
      // Safety: a paused run stops every robot; nothing drives them until it resumes.
      for (AgentModel* agent : s_.agents) agent->body().stop();
      s_.monitor->record_event({t_us_, "console", 0, 0, "paused by " + a.who});
      if (s_.observer) s_.observer->on_status(s_.monitor->status(t_us_, "paused"));
      if (s_.clock) s_.clock->pause();
      break;
    case ControlAction::Kind::kResume:
      s_.monitor->record_event({t_us_, "console", 0, 0, "resumed by " + a.who});
      if (s_.clock) s_.clock->resume();
      break;
    case ControlAction::Kind::kRtFactor: {
      if (s_.clock) s_.clock->set_factor(a.rt_factor);
      std::ostringstream text;
      text << "real-time factor " << a.rt_factor << " set by " << a.who;
      s_.monitor->record_event({t_us_, "console", 0, 0, text.str()});
      break;
    }
    case ControlAction::Kind::kExit:
      s_.monitor->record_event({t_us_, "console", 0, 0, "ended by " + a.who});
      s_.monitor->end_run("console");
      break;
    case ControlAction::Kind::kReset:
      s_.monitor->record_event({t_us_, "console", 0, 0, "reset by " + a.who + ": the run starts over"});
      s_.monitor->end_run("reset");
      break;
    case ControlAction::Kind::kMode: {
      ConsoleOrder o;
      o.kind = ConsoleOrder::Kind::kMode;
      o.central = a.central;
      state_.push_back(o);
      s_.monitor->set_central(a.central);
      s_.monitor->record_event({t_us_, "console", 0, 0,
                                std::string("mode ") + (a.central ? "central" : "distributed") + " set by " + a.who});
      break;
    }
    case ControlAction::Kind::kDrive: {
      ConsoleOrder o;
      o.kind = ConsoleOrder::Kind::kDrive;
      o.robot_id = a.robot_id;
      o.wheels = {a.left, a.right};
      o.until_us = t_us_ + seconds_to_us(a.duration_s);
      state_.push_back(o);
      // A held drive (the web panel's, renewed every few tenths of a second) is one
      // event while its speeds stay and it does not lapse, not one per renewal.
      const auto last = drives_.find(a.robot_id);
      const bool renewal = last != drives_.end() && last->second.wheels == o.wheels && last->second.until_us >= t_us_ &&
                           last->second.who == a.who;
      drives_[a.robot_id] = {o.wheels, o.until_us, a.who};
      if (renewal) break;
      std::ostringstream text;
      text << "robot " << a.robot_id << " driven " << a.left << " " << a.right << " for " << a.duration_s << " s by "
           << a.who;
      s_.monitor->record_event({t_us_, "console", a.robot_id, 0, text.str()});
      break;
    }
    case ControlAction::Kind::kVision: {
      if (!s_.camera) break;  // checked before: the run has a camera
      vision::VisionSettings settings = s_.camera->vision();
      std::ostringstream text;
      text << "vision";
      for (const auto& [name, value] : a.vision) {
        if (vision::set_vision_setting(settings, name, value)) return;  // checked before
        text << " " << name << " " << value;
      }
      if (vision::check_vision_settings(settings)) return;
      s_.camera->set_vision(settings);
      text << " set by " << a.who;
      s_.monitor->record_event({t_us_, "console", 0, 0, text.str()});
      // Viewers see the new settings at once, not at the next second's status.
      if (s_.observer)
        s_.observer->on_status(s_.monitor->status(t_us_, s_.clock && s_.clock->paused() ? "paused" : "running"));
      break;
    }
    case ControlAction::Kind::kRefused:
      s_.monitor->record_event({t_us_, "console", 0, 0, "refused " + a.what + " from " + a.who});
      break;
  }
}

std::optional<std::string> ActionChecker::operator()(const ControlAction& a) {
  switch (a.kind) {
    case ControlAction::Kind::kPause:
      if (!realtime) return "a fast run cannot be paused (it is not paced to the clock)";
      if (paused->exchange(true)) return "the run is paused already";
      return std::nullopt;
    case ControlAction::Kind::kResume:
      if (!paused->exchange(false)) return "the run is not paused";
      return std::nullopt;
    case ControlAction::Kind::kRtFactor:
      if (!realtime) return "a fast run has no real-time factor";
      if (has_real && a.rt_factor != 1.0) return "a run with real robots runs at a factor of 1";
      if (!(a.rt_factor > 0.0) || !std::isfinite(a.rt_factor)) return "the factor must be a number above 0";
      return std::nullopt;
    case ControlAction::Kind::kMode:
      if (!has_convoy) return "this run has no convoy, so no mode to switch";
      if (central_now->exchange(a.central) == a.central) {
        return std::string("the convoy is in ") + (a.central ? "central" : "distributed") + " mode already";
      }
      return std::nullopt;
    case ControlAction::Kind::kDrive:
      if (!robot_ids.contains(a.robot_id)) return "this run has no robot " + std::to_string(a.robot_id);
      if (paused->load()) return "the run is paused: resume it first";
      if (std::abs(a.left) > 127 || std::abs(a.right) > 127) return "wheel speeds are -127..127 (Khepera units)";
      if (!(a.duration_s > 0.0) || !std::isfinite(a.duration_s)) return "the seconds must be above 0";
      return std::nullopt;
    case ControlAction::Kind::kVision: {
      if (!vision_now) return std::string("this run has no camera, so no vision settings");
      if (a.vision.empty()) return std::string("no vision setting given");
      vision::VisionSettings s = *vision_now;
      for (const auto& [name, value] : a.vision) {
        if (auto why = vision::set_vision_setting(s, name, value)) return why;
      }
      if (auto why = vision::check_vision_settings(s)) return why;
      vision_now = s;
      return std::nullopt;
    }
    case ControlAction::Kind::kExit:
    case ControlAction::Kind::kReset:
    case ControlAction::Kind::kRefused: return std::nullopt;
  }
  return "unknown action";
}

}  // namespace rilbed::run
