"""rilbed from Python: controllers written in Python, and runs started and read from scripts.

A controller is a class that subclasses :class:`rilbed.Controller`; a scenario names it with
``controller: {python: FILE, class: NAME}``. ``rilbed.run(...)`` runs a scenario through the
same run session as ``rilbed run`` and returns its summary; ``rilbed.read_run(folder)``
reads a run folder's trajectories and events.

Inside a run (the rilbed binary's embedded interpreter) the controller API comes from the
built-in module ``_rilbed_embedded``; in any other ``/usr/bin/python3`` (with
``PYTHONPATH=build/python``) from the extension module ``rilbed._rilbed``.
"""

import os as _os

try:
    import _rilbed_embedded as _api  # inside a run of the rilbed binary

    _IN_RUN = True
except ImportError:
    from . import _rilbed as _api

    _IN_RUN = False
    # What rilbed finds beside its binary (built-in plug-ins, robot models, the binary
    # that agent processes run), found beside this build's binary instead: this process's
    # executable is python3. The extension lives in <build>/python/rilbed/.
    _BUILD = _os.path.dirname(_os.path.dirname(_os.path.dirname(_os.path.abspath(_api.__file__))))
    for _variable, _name in (("RILBED_BINARY", "rilbed"), ("RILBED_PLUGIN_DIR", "plugins"), ("RILBED_ROBOT_DIR", "robots")):
        if _os.path.exists(_os.path.join(_BUILD, _name)):
            _os.environ.setdefault(_variable, _os.path.join(_BUILD, _name))

Input = _api.Input
SwarmInput = _api.SwarmInput
Output = _api.Output
Pose = _api.Pose
Beacon = _api.Beacon
Odometer = _api.Odometer
TeamMember = _api.TeamMember
wheels_from_twist = _api.wheels_from_twist
METRES_PER_SECOND_PER_UNIT = _api.METRES_PER_SECOND_PER_UNIT
MAX_WHEEL_UNITS = _api.MAX_WHEEL_UNITS
WHEEL_BASE_M = _api.WHEEL_BASE_M
PROXIMITY_COUNT = _api.PROXIMITY_COUNT
PROXIMITY_MAX = _api.PROXIMITY_MAX
# What a robot knows of a tape network on board (docs/track-networks.md).
TrackSensorConfig = _api.TrackSensorConfig
TrackArray = _api.TrackArray
TrackReadingConfig = _api.TrackReadingConfig
TrackArrayReading = _api.TrackArrayReading
arm_sides = _api.arm_sides
read_track_array = _api.read_track_array
TrackFeatureKind = _api.TrackFeatureKind
track_feature_name = _api.track_feature_name
BranchScanConfig = _api.BranchScanConfig
BranchScan = _api.BranchScan
ScanResult = _api.ScanResult

from ._controller import Controller  # noqa: E402
from ._runs import RunError, read_run, run  # noqa: E402

__all__ = [
    "Controller",
    "Input",
    "SwarmInput",
    "Output",
    "Pose",
    "Beacon",
    "Odometer",
    "TeamMember",
    "wheels_from_twist",
    "run",
    "read_run",
    "RunError",
    "METRES_PER_SECOND_PER_UNIT",
    "MAX_WHEEL_UNITS",
    "WHEEL_BASE_M",
    "PROXIMITY_COUNT",
    "PROXIMITY_MAX",
    "TrackSensorConfig",
    "TrackArray",
    "TrackReadingConfig",
    "TrackArrayReading",
    "arm_sides",
    "read_track_array",
    "TrackFeatureKind",
    "track_feature_name",
    "BranchScanConfig",
    "BranchScan",
    "ScanResult",
]
