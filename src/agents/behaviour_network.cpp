#include "agents/behaviour_network.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rilbed::agents {

std::string_view behaviour_name(Behaviour b) {
  switch (b) {
    case Behaviour::kSearch: return "search";
    case Behaviour::kFollow: return "follow";
    case Behaviour::kWait: return "wait";
    case Behaviour::kAvoid: return "avoid";
  }
  return "unknown";
}

BehaviourNetwork::BehaviourNetwork(BehaviourNetworkConfig config) : config_(config) {
  if (!(config_.time_constant_s > 0.0)) throw std::invalid_argument("behaviour network: time_constant_s must be > 0");
}

BehaviourNetworkState BehaviourNetwork::update(const BehaviourNetworkState& state, const BehaviourInputs& inputs,
                                               double dt_s) const {
  if (!(dt_s > 0.0)) throw std::invalid_argument("behaviour network: dt_s must be > 0");
  BehaviourNetworkState next = state;
  BehaviourInputs input = inputs;
  for (double& x : input) x = std::clamp(std::isfinite(x) ? x : 0.0, 0.0, 1.0);
  // Explicit Euler is stable for steps up to tau; a quarter keeps it accurate, so a
  // 100 ms and a 20 ms control period give the same dynamics.
  const int substeps = std::max(1, static_cast<int>(std::ceil(dt_s / (0.25 * config_.time_constant_s))));
  const double h = dt_s / substeps / config_.time_constant_s;
  for (int s = 0; s < substeps; ++s) {
    std::array<double, kBehaviourCount> a = next.activation;  // simultaneous update
    for (std::size_t i = 0; i < kBehaviourCount; ++i) {
      double inhibition = 0.0;
      for (std::size_t j = 0; j < kBehaviourCount; ++j) {
        if (j != i) inhibition += config_.inhibition[i][j] * next.activation[j];
      }
      a[i] = std::clamp(next.activation[i] + h * (input[i] - next.activation[i] - inhibition), 0.0, 1.0);
    }
    next.activation = a;
  }
  // Winner: the largest activation; the incumbent keeps a tie.
  auto winner = static_cast<std::size_t>(state.active);
  double best = next.activation[winner];
  for (std::size_t i = 0; i < kBehaviourCount; ++i) {
    if (next.activation[i] > best) {
      best = next.activation[i];
      winner = i;
    }
  }
  next.active = best > 0.0 ? static_cast<Behaviour>(winner) : config_.idle;
  return next;
}

}  // namespace rilbed::agents
