"""The base class of Python controllers."""


class Controller:
    """A robot controller written in Python.

    Subclass it and define one of:

    - ``step(self, inp)``: one robot per call. ``inp`` is a :class:`rilbed.Input`; return
      ``(left, right)`` wheel speeds in Khepera units (8 mm/s each, at most 127 either way),
      or ``rilbed.Output(left, right, behaviour="...")``. One instance per robot.
    - ``step_all(self, inp)``: every robot the class controls at once. ``inp`` is a
      :class:`rilbed.SwarmInput` of NumPy arrays with a row per robot, in ``inp.robot_id``'s
      order; return an array of shape (n, 2), or ``(that array, behaviour)`` with behaviour
      one string, a list of n strings or a NumPy array of n strings. One instance per group of robots with the same ``params``.

    ``__init__(self, params)`` gets the scenario's ``params`` as a dict of numbers; raise
    (``ValueError``, ...) to refuse them: the run does not start, and says why.
    """

    #: Set True in a subclass to receive the team broadcast (``inp.team``).
    wants_team = False
    #: Set True when its robots form paper 001's convoy (robot k follows robot k - 1, IDs
    #: 1..N): the run then watches them for formation (the summary's ``formed`` and
    #: ``formation_time_s``), as it watches rilbed's own ``convoy``.
    forms_convoy = False

    def __init__(self, params=None):
        self.params = dict(params or {})

    def finish(self):
        """Called once when the run ends, after the last step."""

    def done(self):
        """Whether the controller reached its goal (runs with --stop-when-done end when all are)."""
        return False
