"""The convoy of paper 001 (section 5) in Python: rilbed's `convoy` controller, ported.

Robot k follows robot k - 1 (the robots are numbered 1..N by their IDs). Each robot's
behaviour network chooses between search (drive to the leader while it is far), follow
(keep a standoff behind it), wait (the head, and a robot that does not know where its
leader is) and avoid (turn away from what the IR sensors see). A robot knows the others
only from the team broadcast (``wants_team``), as in the distributed mode of the paper.

    controller: {python: ../examples/python/convoy.py, class: Convoy}
    params: {standoff_m: 0.12}

Every parameter is optional; the defaults are the C++ convoy's (scenarios/README.md).
"""

import math

import rilbed

SEARCH, FOLLOW, WAIT, AVOID = range(4)
NAMES = ("search", "follow", "wait", "avoid")
# inhibition[i][j]: how strongly behaviour j's activation suppresses behaviour i's.
INHIBITION = (
    (0.0, 0.6, 0.3, 1.2),  # search
    (0.6, 0.0, 0.3, 1.2),  # follow
    (0.4, 0.4, 0.0, 1.2),  # wait
    (0.1, 0.1, 0.1, 0.0),  # avoid
)
CONTACT_M = 0.055  # two Khepera radii: where the repulsion is strongest

DEFAULTS = {
    "standoff_m": 0.12,  # distance kept behind the leader, centre to centre
    "engage_m": 0.22,  # a leader nearer than this is followed, farther searched for
    "engage_ramp_m": 0.04,  # width of the hand-over between search and follow
    "hold_tolerance_m": 0.015,  # within this of the standoff a follower holds and does not avoid
    "avoid_low": 0.35,  # proximity level (fraction of full scale) where avoidance starts
    "avoid_high": 0.7,  # and where it is fully called for
    "repulse_radius_m": 0.12,  # other robots nearer than this bend the course away
    "repulse_gain": 1.0,  # strength of that bend at contact
    "max_speed_mps": 0.15,
    "max_reverse_mps": 0.04,
    "turn_gain": 3.0,  # turn rate per radian of heading error, 1/s
    "max_turn_radps": 4.0,
    "slow_zone_m": 0.08,  # the speed ramps down to zero over this before the standoff
    "time_constant_s": 0.2,  # the behaviour network's
}


def clamp(x, low, high):
    return min(max(x, low), high)


def wrap_pi(rad):
    """An angle in radians in [-pi, pi)."""
    return (rad + math.pi) % (2.0 * math.pi) - math.pi


def obstacle_level(p, low, high):
    nearest = max(p[0], p[1], p[2], p[3], p[4], p[5]) / rilbed.PROXIMITY_MAX
    if high <= low:
        return 1.0 if nearest >= high else 0.0
    return clamp((nearest - low) / (high - low), 0.0, 1.0)


class BehaviourNetwork:
    """Activations that rise towards their inputs and inhibit each other (tau, Euler steps of tau / 4)."""

    def __init__(self, time_constant_s):
        if not time_constant_s > 0:
            raise ValueError(f"time_constant_s must be > 0, not {time_constant_s}")
        self.tau = time_constant_s
        self.activation = [0.0, 0.0, 0.0, 0.0]
        self.active = WAIT

    def update(self, inputs, dt_s):
        inputs = [clamp(x if math.isfinite(x) else 0.0, 0.0, 1.0) for x in inputs]
        substeps = max(1, math.ceil(dt_s / (0.25 * self.tau)))
        h = dt_s / substeps / self.tau
        a = self.activation
        for _ in range(substeps):
            a = [
                clamp(a[i] + h * (inputs[i] - a[i] - sum(INHIBITION[i][j] * a[j] for j in range(4) if j != i)), 0.0, 1.0)
                for i in range(4)
            ]
        self.activation = a
        winner, best = self.active, a[self.active]  # the incumbent keeps a tie
        for i in range(4):
            if a[i] > best:
                winner, best = i, a[i]
        self.active = winner if best > 0.0 else WAIT
        return self.active


class Convoy(rilbed.Controller):
    """Convoy team formation (paper 001): robot k follows robot k - 1, from the team broadcast."""

    wants_team = True
    forms_convoy = True  # the run watches the robots for formation, as for the C++ convoy

    def __init__(self, params):
        super().__init__(params)
        unknown = set(params) - set(DEFAULTS)
        if unknown:
            raise ValueError(f"unknown params {sorted(unknown)}; Convoy takes {', '.join(DEFAULTS)}")
        self.c = dict(DEFAULTS, **params)
        for key, value in self.c.items():
            if value < 0:
                raise ValueError(f"{key} must not be negative, not {value}")
        self.network = BehaviourNetwork(self.c["time_constant_s"])
        self.last_t_us = None

    def step(self, inp):
        rank = inp.robot_id
        leader, others = None, []
        for m in inp.team:
            if m.id == rank:
                continue
            if m.id == rank - 1:
                leader = m.pose
            elif m.id != rank + 1:  # the follower keeps its own distance
                others.append((m.pose.x_m, m.pose.y_m))
        dt_s = 0.1 if self.last_t_us is None else max(1e-3, (inp.t_us - self.last_t_us) * 1e-6)
        self.last_t_us = inp.t_us
        active = self.network.update(self.inputs(rank, inp.pose, leader, inp.proximity), dt_s)
        return rilbed.Output(*self.wheels(active, inp.pose, leader, inp.proximity, others), behaviour=NAMES[active])

    def inputs(self, rank, me, leader, proximity):
        c = self.c
        inputs = [0.0, 0.0, 0.0, 0.0]
        if rank == 1 or leader is None or me is None:
            inputs[WAIT] = 1.0  # the head waits; so does a robot that cannot place itself or its leader
            return inputs
        distance = math.hypot(leader.x_m - me.x_m, leader.y_m - me.y_m)
        far = clamp((distance - c["engage_m"]) / c["engage_ramp_m"] + 0.5, 0.0, 1.0)
        inputs[SEARCH], inputs[FOLLOW] = far, 1.0 - far
        # Only while driving on: a follower holding its standoff sees its neighbours all the time.
        if proximity is not None and distance > c["standoff_m"] + c["hold_tolerance_m"]:
            inputs[AVOID] = obstacle_level(proximity, c["avoid_low"], c["avoid_high"])
        return inputs

    def wheels(self, active, me, leader, proximity, others):
        if active == AVOID:
            return self.steer_away(proximity) if proximity is not None else (0, 0)
        if active in (SEARCH, FOLLOW) and me is not None and leader is not None:
            push = self.repulsion(me, others)
            if active == FOLLOW:  # near the leader only the robots right beside matter
                push = (0.5 * push[0], 0.5 * push[1])
            return self.steer_to(me, (leader.x_m, leader.y_m), push)
        return (0, 0)

    def repulsion(self, me, others):
        c = self.c
        px = py = 0.0
        for ox, oy in others:
            ax, ay = me.x_m - ox, me.y_m - oy
            d = math.hypot(ax, ay)
            if d < 1e-9 or d >= c["repulse_radius_m"]:
                continue
            strength = c["repulse_gain"] * clamp((c["repulse_radius_m"] - d) / (c["repulse_radius_m"] - CONTACT_M), 0.0, 1.0)
            px += ax / d * strength
            py += ay / d * strength
        return (px, py)

    def steer_to(self, me, target, push):
        c = self.c
        tx, ty = target[0] - me.x_m, target[1] - me.y_m
        distance = math.hypot(tx, ty)
        if distance < 1e-9:
            return (0, 0)
        cx, cy = tx / distance + push[0], ty / distance + push[1]
        if math.hypot(cx, cy) < 1e-9:
            cx, cy = tx / distance, ty / distance
        error = wrap_pi(math.atan2(cy, cx) - me.theta_rad)
        turn = clamp(c["turn_gain"] * error, -c["max_turn_radps"], c["max_turn_radps"])
        # Zero at the standoff, negative inside it; only while roughly facing the course.
        approach = clamp((distance - c["standoff_m"]) / c["slow_zone_m"], -1.0, 1.0)
        speed = approach * (c["max_speed_mps"] if approach >= 0 else c["max_reverse_mps"])
        facing = math.cos(error)
        speed = speed * facing if facing > 0.0 else 0.0
        return rilbed.wheels_from_twist(speed, turn)

    def steer_away(self, p):
        c = self.c
        scale = 1.0 / rilbed.PROXIMITY_MAX
        left = scale * (0.5 * p[0] + p[1] + p[2])
        right = scale * (p[3] + p[4] + 0.5 * p[5])
        front = scale * max(p[1], p[2], p[3], p[4])
        turn = c["max_turn_radps"] * clamp(right - left, -1.0, 1.0)
        if abs(right - left) < 0.1 and front > 0.3:
            turn = c["max_turn_radps"]  # dead ahead with nothing to choose between: turn left
        speed = c["max_speed_mps"] * clamp(0.6 - front, -0.3, 0.6)
        return rilbed.wheels_from_twist(speed, turn)
