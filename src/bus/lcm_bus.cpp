#include "bus/lcm_bus.hpp"

#include "bus/lcm_checked.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <type_traits>
#include <utility>

namespace rilbed::bus {

LcmSubscription::LcmSubscription(lcm::LCM& lcm, const std::string& channel, Handler handler)
    : lcm_(lcm.getUnderlyingLCM()), handler_(std::move(handler)) {
  if (lcm_) subscription_ = lcm_subscribe(lcm_, channel.c_str(), &LcmSubscription::dispatch, this);
}

LcmSubscription::~LcmSubscription() {
  if (lcm_ && subscription_) lcm_unsubscribe(lcm_, subscription_);
}

void LcmSubscription::dispatch(const lcm_recv_buf_t* rbuf, const char* channel, void* self) {
  auto* s = static_cast<LcmSubscription*>(self);
  s->handler_(channel, rbuf->data, static_cast<std::size_t>(rbuf->data_size));
}

std::string agent_reply_url(const std::string& url) {
  // udpm://GROUP:PORT?OPTIONS, or udpm:// (LCM's default 239.255.76.67:7667), or empty (the same).
  std::string u = url.empty() ? "udpm://239.255.76.67:7667" : url;
  if (u.rfind("udpm://", 0) != 0) return url;
  const std::size_t opts = u.find('?');
  std::string address = u.substr(7, opts == std::string::npos ? std::string::npos : opts - 7);
  const std::string rest = opts == std::string::npos ? "" : u.substr(opts);
  if (address.empty()) address = "239.255.76.67:7667";
  const std::size_t colon = address.rfind(':');
  int port = 7667;
  if (colon != std::string::npos) {
    try {
      port = std::stoi(address.substr(colon + 1));
    } catch (const std::exception&) {
      return url;  // LCM will refuse it itself
    }
    address.resize(colon);
  }
  if (port < 1 || port >= 65535) return url;
  return "udpm://" + address + ":" + std::to_string(port + 1) + rest;
}

Channels Channels::with_prefix(const std::string& prefix) {
  Channels c;
  c.poses = prefix + c.poses;
  c.events = prefix + c.events;
  c.status = prefix + c.status;
  c.world = prefix + c.world;
  c.summary = prefix + c.summary;
  c.console = prefix + c.console;
  c.console_reply = prefix + c.console_reply;
  c.agent_hello = prefix + c.agent_hello;
  c.quantum = prefix + c.quantum;
  c.quantum_reply = prefix + c.quantum_reply;
  c.wheels = prefix + c.wheels;
  c.sensors = prefix + c.sensors;
  c.detections = prefix + c.detections;
  c.frames = prefix + c.frames;
  c.camera = prefix + c.camera;
  c.vision = prefix + c.vision;
  c.sensor_layout = prefix + c.sensor_layout;
  c.robot_bodies = prefix + c.robot_bodies;
  c.sensor_models = prefix + c.sensor_models;
  return c;
}

std::optional<std::string> check_channel_prefix(const std::string& prefix) {
  for (const char c : prefix) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') {
      return "channel prefix '" + prefix + "' may hold only letters, digits and '_'";
    }
  }
  // The longest channel, RILBED_CONSOLE_REPLY, is 20 bytes; LCM allows 63.
  if (prefix.size() > 50) return "channel prefix '" + prefix + "' is longer than 50 characters";
  return std::nullopt;
}

std::unique_ptr<lcm::LCM> open_lcm(const std::string& url, std::string& error) {
  auto lcm = std::make_unique<lcm::LCM>(url);
  if (!lcm->good()) {
    error = "cannot open the LCM bus '" + url + "' (a URL such as memq:// or udpm://239.255.76.67:7667?ttl=0)";
    return nullptr;
  }
  return lcm;
}

}  // namespace rilbed::bus
