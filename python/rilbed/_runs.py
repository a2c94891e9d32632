"""Runs from Python: start one as ``rilbed run`` would, and read a run folder back."""

import csv
import json
import os



def _native():
    """The extension module, or None inside a run of the rilbed binary (no runs within runs)."""
    from . import _IN_RUN, _api

    return None if _IN_RUN else _api


class RunError(RuntimeError):
    """A run that could not start or did not finish; the message says why."""


_TRAJECTORY_HEADER = ["t_s", "id", "x_m", "y_m", "theta_deg", "behaviour"]
_EVENTS_HEADER = ["t_s", "kind", "id", "other", "detail"]


def run(scenario, seed=1, duration_s=None, out=None, overrides=None, **options):
    """Runs ``scenario`` once and returns its summary as a dict.

    scenario: a scenario file's path, or a dict in the scenario's schema (relative paths in
        it start at the working directory).
    seed: initial poses, wheel slip and sensor noise derive from it.
    duration_s: simulated seconds (default: the scenario's ``duration_s``).
    out: a run folder to write (as ``rilbed run --out`` writes it); None: none.
    overrides: ``{"convoy.standoff_m": 0.1, "robots.0.params.speed_mps": 0.1, ...}``,
        changes to the scenario by path before it is read.
    options: ``fast`` (default True), ``realtime``, ``rt_factor``, ``stop_when_formed``, ``stop_when_done``,
        ``threads``, ``mode`` ('central' or 'distributed'), ``on_controller_error``
        ('end-run' or 'stop-robot'), ``all_virtual``, ``lcm_url``, ``record``.

    The summary holds ``seed``, ``formed``, ``formation_time_s``, ``collisions``,
    ``robot_collisions``, ``simulated_s``, ``ended_by``, ``controller_overruns``,
    ``controller_failed``, ... and ``out``. Raises RunError when the run fails.
    """
    native = _native()
    if native is None:
        raise RunError("rilbed.run() is for scripts, not for controllers inside a run")
    if isinstance(scenario, dict):
        path = os.path.join(os.getcwd(), "scenario-from-python.yaml")
        text = json.dumps(scenario)
    else:
        path = os.fspath(scenario)
        text = ""
    pairs = [[str(k), v] for k, v in (overrides or {}).items()]
    if not options.get("realtime"):
        options.setdefault("fast", True)
    try:
        summary = native._run_session(
            path,
            text,
            json.dumps(pairs),
            int(seed),
            -1.0 if duration_s is None else float(duration_s),
            "" if out is None else os.fspath(out),
            json.dumps(options),
        )
    except RuntimeError as e:
        raise RunError(str(e)) from None
    return json.loads(summary)


def _read_csv(path, header, types):
    with open(path, newline="") as f:
        reader = csv.reader(f)
        first = next(reader, None)
        if first != header:
            raise ValueError(f"{path}: line 1 is {first}, not the header {','.join(header)}")
        rows = []
        for number, row in enumerate(reader, start=2):
            if len(row) != len(header):
                raise ValueError(f"{path}:{number}: {len(row)} fields, not {len(header)}")
            try:
                rows.append(tuple(t(v) for t, v in zip(types, row)))
            except ValueError as e:
                raise ValueError(f"{path}:{number}: {e}") from None
    return rows


def read_run(folder):
    """The trajectories and events of a run folder: ``(trajectories, events)``.

    Each is a NumPy structured array (fields as the CSV headers: trajectories ``t_s, id,
    x_m, y_m, theta_deg, behaviour``; events ``t_s, kind, id, other, detail``), or a pandas
    DataFrame when pandas is installed. Raises ValueError for a file whose header or rows
    are not what rilbed writes, naming the file and the line.
    """
    import numpy as np

    folder = os.fspath(folder)
    traj = _read_csv(os.path.join(folder, "trajectories.csv"), _TRAJECTORY_HEADER, (float, int, float, float, float, str))
    events = _read_csv(os.path.join(folder, "events.csv"), _EVENTS_HEADER, (float, str, int, int, str))
    traj_dtype = [("t_s", "f8"), ("id", "i8"), ("x_m", "f8"), ("y_m", "f8"), ("theta_deg", "f8"), ("behaviour", "U64")]
    event_dtype = [("t_s", "f8"), ("kind", "U32"), ("id", "i8"), ("other", "i8"), ("detail", "O")]
    t = np.array(traj, dtype=traj_dtype)
    e = np.array(events, dtype=event_dtype)
    try:
        import pandas as pd
    except ImportError:
        return t, e
    return pd.DataFrame(t), pd.DataFrame(e)
