// Decoding LCM messages from the network safely. lcm-gen's decoders size each array by
// its count field and each string by its length field before reading them, so a corrupt
// or hostile message can ask for gigabytes or make the decoder read far past its buffer
// (a string length of 0x80000000 wraps around). Every rilbed message is therefore walked
// first, field by field, with every count and length checked against the bytes that are
// left; only a message that passes reaches lcm-gen's decoder.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "rilbed/agent_hello_t.hpp"
#include "rilbed/camera_t.hpp"
#include "rilbed/console_command_t.hpp"
#include "rilbed/console_reply_t.hpp"
#include "rilbed/detections_t.hpp"
#include "rilbed/event_t.hpp"
#include "rilbed/frame_t.hpp"
#include "rilbed/poses_t.hpp"
#include "rilbed/quantum_reply_t.hpp"
#include "rilbed/quantum_t.hpp"
#include "rilbed/robot_bodies_t.hpp"
#include "rilbed/sensor_layout_t.hpp"
#include "rilbed/sensor_models_t.hpp"
#include "rilbed/sensors_t.hpp"
#include "rilbed/status_t.hpp"
#include "rilbed/summary_t.hpp"
#include "rilbed/vision_settings_t.hpp"
#include "rilbed/wheels_t.hpp"
#include "rilbed/world_t.hpp"

namespace rilbed::bus {

/// Whether `size` bytes at `data` are one whole, well-formed encoding of a `Message`
/// (one of rilbed's types), every count and string length within the bytes.
template <typename Message>
bool well_formed(const void* data, std::size_t size);

/// Decodes `data` as a `Message` after well_formed(); false when it is not one. Never
/// throws, never allocates more than a small multiple of `size`.
template <typename Message>
bool decode_checked(const void* data, std::size_t size, Message& message) {
  if (size > static_cast<std::size_t>(std::numeric_limits<int>::max()) || !well_formed<Message>(data, size))
    return false;
  try {
    const int length = static_cast<int>(size);
    return message.decode(data, 0, length) == length;
  } catch (const std::exception&) {
    return false;
  }
}

/// Publishes `message` on `channel` as the bytes its encoder wrote. (LCM's own
/// publish(channel, &message) sends getEncodedSize() bytes, but a string holding a 0 byte
/// is written only up to it: the message would go out with stray bytes at its end, which
/// every careful reader refuses.) Returns LCM's status (0 when sent).
template <typename Message>
int publish_encoded(lcm::LCM& lcm, const std::string& channel, const Message& message) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  const int written = message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  if (written < 0) return -1;
  return lcm.publish(channel, bytes.data(), static_cast<unsigned>(written));
}

}  // namespace rilbed::bus
