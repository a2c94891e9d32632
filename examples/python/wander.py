"""Braitenberg wanderers in Python: rilbed's `wander` controller, written twice.

`Wander` decides for one robot per call (`step`); `SwarmWander` for every robot at once with
NumPy (`step_all`). Both do what the C++ `wander` does, operation for operation, so a run
with either gives the C++ controller's trajectories (the tests compare them), and the
benchmarks compare their cost with it.

    controller: {python: ../examples/python/wander.py, class: Wander}
    params: {speed_mps: 0.1}
"""

import numpy as np

import rilbed

PROXIMITY_SCALE = 1.0 / rilbed.PROXIMITY_MAX
MAX_SPEED_MPS = 0.15  # the steering's cruising speed when avoiding (SteeringConfig)
MAX_TURN_RADPS = 4.0


def check_params(params):
    """The speed in m/s from `params` (default 0.1), refused outside 0..1.016 m/s."""
    unknown = set(params) - {"speed_mps", "avoid_low", "avoid_high"}
    if unknown:
        raise ValueError(f"unknown params {sorted(unknown)}; Wander takes speed_mps, avoid_low, avoid_high")
    speed = params.get("speed_mps", 0.1)
    if not 0.0 <= speed <= rilbed.MAX_WHEEL_UNITS * rilbed.METRES_PER_SECOND_PER_UNIT:
        raise ValueError(f"speed_mps must be between 0 and 1.016 m/s, not {speed}")
    return speed, params.get("avoid_low", 0.1), params.get("avoid_high", 0.5)


class Wander(rilbed.Controller):
    """A Braitenberg wanderer: straight ahead in the open, turning away from what its IR sensors see."""

    def __init__(self, params):
        super().__init__(params)
        self.speed_mps, self.low, self.high = check_params(params)

    def step(self, inp):
        p = inp.proximity
        if p is not None:
            nearest = PROXIMITY_SCALE * max(p[0], p[1], p[2], p[3], p[4], p[5])
            if min(max((nearest - self.low) / (self.high - self.low), 0.0), 1.0) > 0.0:
                return rilbed.Output(*self.steer_away(p), behaviour="avoid")
        return rilbed.Output(*rilbed.wheels_from_twist(self.speed_mps, 0.0), behaviour="cruise")

    @staticmethod
    def steer_away(p):
        left = PROXIMITY_SCALE * (0.5 * p[0] + p[1] + p[2])
        right = PROXIMITY_SCALE * (p[3] + p[4] + 0.5 * p[5])
        front = PROXIMITY_SCALE * max(p[1], p[2], p[3], p[4])
        turn = MAX_TURN_RADPS * min(max(right - left, -1.0), 1.0)
        if abs(right - left) < 0.1 and front > 0.3:
            turn = MAX_TURN_RADPS  # dead ahead with nothing to choose between: turn left
        speed = MAX_SPEED_MPS * min(max(0.6 - front, -0.3), 0.6)
        return rilbed.wheels_from_twist(speed, turn)


def wheels_from_twist(speed_mps, turn_rate_radps):
    """rilbed.wheels_from_twist for arrays: (n, 2) wheel units, rounded half away from zero."""
    half = 0.5 * turn_rate_radps * rilbed.WHEEL_BASE_M
    left = (speed_mps - half) / rilbed.METRES_PER_SECOND_PER_UNIT
    right = (speed_mps + half) / rilbed.METRES_PER_SECOND_PER_UNIT
    biggest = np.maximum(np.abs(left), np.abs(right))
    scale = np.where(biggest > rilbed.MAX_WHEEL_UNITS, rilbed.MAX_WHEEL_UNITS / np.maximum(biggest, 1e-300), 1.0)
    wheels = np.stack([left * scale, right * scale], axis=1)
    return np.sign(wheels) * np.floor(np.abs(wheels) + 0.5)


class SwarmWander(rilbed.Controller):
    """Wander for a whole swarm in one NumPy call per control step."""

    def __init__(self, params):
        super().__init__(params)
        self.speed_mps, self.low, self.high = check_params(params)

    def step_all(self, inp):
        # A robot without IR sensors has a NaN row: every comparison with NaN is false, so
        # it cruises. The maxima are taken column by column (NumPy's reduction along a
        # short row is several times slower).
        p = inp.proximity
        c = [p[:, k] for k in range(6)]
        nearest = PROXIMITY_SCALE * np.maximum.reduce(c)
        avoiding = np.clip((nearest - self.low) / (self.high - self.low), 0.0, 1.0) > 0.0
        left = PROXIMITY_SCALE * (0.5 * c[0] + c[1] + c[2])
        right = PROXIMITY_SCALE * (c[3] + c[4] + 0.5 * c[5])
        front = PROXIMITY_SCALE * np.maximum.reduce(c[1:5])
        turn = MAX_TURN_RADPS * np.clip(right - left, -1.0, 1.0)
        turn = np.where((np.abs(right - left) < 0.1) & (front > 0.3), MAX_TURN_RADPS, turn)
        speed = MAX_SPEED_MPS * np.clip(0.6 - front, -0.3, 0.6)
        speed = np.where(avoiding, speed, self.speed_mps)
        turn = np.where(avoiding, turn, 0.0)
        return wheels_from_twist(speed, turn), np.where(avoiding, "avoid", "cruise")
