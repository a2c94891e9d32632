"""Controllers that go wrong in each way a lab's can, for the tests of rilbed's errors."""

import rilbed


class RaisesAtTwoSeconds(rilbed.Controller):
    """Drives ahead, then raises in robot `robot`'s step from t = 2 s."""

    def __init__(self, params):
        super().__init__(params)
        self.robot = int(params.get("robot", 2))

    def step(self, inp):
        if inp.robot_id == self.robot and inp.t_us >= 2_000_000:
            return self.broken_sensor_model(inp)
        return (5, 5)

    def broken_sensor_model(self, inp):
        return inp.proximity[0] / 0  # ZeroDivisionError, on this line


class ReturnsText(rilbed.Controller):
    def step(self, inp):
        return "forward"


class ReturnsThree(rilbed.Controller):
    def step(self, inp):
        return (1, 2, 3)


class ReturnsNaN(rilbed.Controller):
    def step(self, inp):
        return (float("nan"), 0)


class RefusesParams(rilbed.Controller):
    def __init__(self, params):
        super().__init__(params)
        if params.get("gain", 1.0) <= 0:
            raise ValueError(f"gain must be positive, not {params['gain']}")

    def step(self, inp):
        return (0, 0)


class NoStep(rilbed.Controller):
    pass


class BothSteps(rilbed.Controller):
    def step(self, inp):
        return (0, 0)

    def step_all(self, inp):
        return None


class NotAController:
    def step(self, inp):
        return (0, 0)


class SwarmWrongShape(rilbed.Controller):
    def step_all(self, inp):
        return [[1, 2, 3]] * len(inp.robot_id)


class SwarmRaises(rilbed.Controller):
    def step_all(self, inp):
        if inp.t_us >= 1_000_000:
            raise RuntimeError("the swarm's model diverged")
        return [[3, 3]] * len(inp.robot_id)


class Slow(rilbed.Controller):
    """Takes 150 ms per step: longer than a 100 ms control period in real time."""

    def step(self, inp):
        import time

        time.sleep(0.15)
        return (0, 0)


class Finishes(rilbed.Controller):
    """Counts its steps and writes them to the file `out` names (params are numbers: an ID)."""

    finished = []

    def __init__(self, params):
        super().__init__(params)
        self.steps = 0

    def step(self, inp):
        self.steps += 1
        return rilbed.Output(2, 2, behaviour="count")

    def finish(self):
        Finishes.finished.append(self.steps)
