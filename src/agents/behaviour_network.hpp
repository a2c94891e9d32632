// Behaviour choice by mutual inhibition (paper 001 §5): every behaviour has an
// activation driven by how well the sensed situation calls for it, each active behaviour
// inhibits the others, and the most active one drives the wheels. The inhibition gives
// hysteresis: a behaviour that has won keeps winning until another's input clearly
// exceeds it, so the robot does not dither between two behaviours on a noisy boundary.
#pragma once

#include <array>
#include <cstddef>
#include <string_view>

namespace rilbed::agents {

/// The convoy's behaviours (paper 001 §5).
enum class Behaviour : std::size_t { kSearch = 0, kFollow, kWait, kAvoid };
inline constexpr std::size_t kBehaviourCount = 4;

/// Lower-case name of a behaviour ("search", "follow", "wait", "avoid"); a static string.
std::string_view behaviour_name(Behaviour b);

/// Knobs of the network's dynamics.
struct BehaviourNetworkConfig {
  /// Time constant of the activations, seconds. Shorter reacts faster to a new
  /// situation, longer filters sensor noise.
  double time_constant_s = 0.2;
  /// inhibition[i][j]: how strongly behaviour j's activation suppresses behaviour i's
  /// (rows and columns in Behaviour order; the diagonal is ignored). Larger gives more
  /// hysteresis and slower switching. By default avoid suppresses everything strongly,
  /// follow and search suppress each other, and wait is suppressed by the other three.
  std::array<std::array<double, kBehaviourCount>, kBehaviourCount> inhibition{{
      // search follow wait  avoid   (inhibitor)
      {{0.0, 0.6, 0.3, 1.2}},  // search
      {{0.6, 0.0, 0.3, 1.2}},  // follow
      {{0.4, 0.4, 0.0, 1.2}},  // wait
      {{0.1, 0.1, 0.1, 0.0}},  // avoid
  }};
  /// Behaviour that wins while no activation exceeds zero (a robot with nothing to do).
  Behaviour idle = Behaviour::kWait;
};

/// The network's state: one activation in [0, 1] per behaviour, and the winner.
struct BehaviourNetworkState {
  std::array<double, kBehaviourCount> activation{};
  Behaviour active = Behaviour::kWait;
};

/// Inputs of one step: how much the situation calls for each behaviour, each in [0, 1].
using BehaviourInputs = std::array<double, kBehaviourCount>;

/// Mutual-inhibition behaviour choice. A pure transition on an explicit state:
/// next = update(state, inputs, dt). No hidden state; copyable.
class BehaviourNetwork {
 public:
  explicit BehaviourNetwork(BehaviourNetworkConfig config = {});

  /// Advances the activations by dt_s (seconds, > 0) under `inputs` (each clamped to
  /// [0, 1]) and picks the winner: the largest activation; ties go to the behaviour
  /// already active, then to the lowest Behaviour value.
  /// a_i += dt/tau * (input_i - a_i - sum_j inhibition[i][j] * a_j), clamped to [0, 1];
  /// dt is split into steps of at most tau/4 so the result does not depend on the
  /// control period's length.
  BehaviourNetworkState update(const BehaviourNetworkState& state, const BehaviourInputs& inputs, double dt_s) const;

  const BehaviourNetworkConfig& config() const { return config_; }

 private:
  BehaviourNetworkConfig config_;
};

}  // namespace rilbed::agents
