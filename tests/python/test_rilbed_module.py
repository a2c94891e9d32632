"""The `rilbed` module from a plain /usr/bin/python3 (PYTHONPATH=build/python): runs from
scripts, their summaries, overrides, run folders read back, and the errors a script sees.
CTest runs it (python_module); `python3 -m unittest` does too."""

import json
import os
import shutil
import tempfile
import unittest

import numpy as np

import rilbed

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
CONVOY = os.path.join(ROOT, "scenarios", "convoy_sim.yaml")
WANDER = os.path.join(ROOT, "examples", "python", "wander.py")


def wander_dict(cls="Wander", robots=4, duration_s=5, params=None):
    robot = {
        "ids": f"1-{robots}",
        "pose": "random",
        "controller": {"python": WANDER, "class": cls},
        "sensors": {"proximity": {"range_m": 0.05, "noise_sd": 3}},
    }
    if params:
        robot["params"] = params
    return {"name": "wander_py", "duration_s": duration_s, "field": {"width_m": 1.5, "height_m": 1.2, "walls": True}, "robots": [robot]}


class RunsFromPython(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="rilbed_py_")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def test_a_file_runs_and_its_folder_reads_back(self):
        out = os.path.join(self.tmp, "run")
        summary = rilbed.run(CONVOY, seed=3, duration_s=20, out=out)
        self.assertEqual(summary["seed"], 3)
        self.assertEqual(summary["simulated_s"], 20.0)
        self.assertEqual(summary["convoy_size"], 8)
        self.assertEqual(summary["out"], out)
        with open(os.path.join(out, "summary.json")) as f:
            self.assertEqual(json.load(f)["seed"], 3)
        trajectories, events = rilbed.read_run(out)
        self.assertEqual(list(trajectories.dtype.names), ["t_s", "id", "x_m", "y_m", "theta_deg", "behaviour"])
        self.assertEqual(sorted(set(trajectories["id"].tolist())), list(range(1, 9)))
        self.assertAlmostEqual(float(trajectories["t_s"].max()), 19.9, places=6)
        self.assertIn("behaviour", set(events["kind"].tolist()))

    def test_the_same_seed_gives_the_same_run(self):
        a = rilbed.run(CONVOY, seed=4, duration_s=15, out=os.path.join(self.tmp, "a"))
        b = rilbed.run(CONVOY, seed=4, duration_s=15, out=os.path.join(self.tmp, "b"))
        ta, _ = rilbed.read_run(a["out"])
        tb, _ = rilbed.read_run(b["out"])
        self.assertTrue(np.array_equal(ta, tb))

    def test_a_dict_runs_a_python_controller(self):
        out = os.path.join(self.tmp, "w")
        summary = rilbed.run(wander_dict(), seed=2, out=out)
        self.assertEqual(summary["ended_by"], "duration")
        trajectories, _ = rilbed.read_run(out)
        self.assertTrue({"cruise", "avoid"} & set(trajectories["behaviour"].tolist()))
        moved = np.abs(np.diff(trajectories[trajectories["id"] == 1]["x_m"])).sum()
        self.assertGreater(moved, 0.05)

    def test_overrides_change_the_scenario_by_path(self):
        slow = rilbed.run(wander_dict(params={"speed_mps": 0.02}), seed=2, out=os.path.join(self.tmp, "s"))
        fast = rilbed.run(wander_dict(params={"speed_mps": 0.02}), seed=2, out=os.path.join(self.tmp, "f"),
                          overrides={"robots.0.params.speed_mps": 0.2, "duration_s": 3})
        self.assertEqual(fast["simulated_s"], 3.0)
        ts, _ = rilbed.read_run(slow["out"])
        tf, _ = rilbed.read_run(fast["out"])
        def path_m(t):
            r = t[t["id"] == 1]
            return float(np.hypot(np.diff(r["x_m"]), np.diff(r["y_m"])).sum() / (r["t_s"][-1] - r["t_s"][0]))
        self.assertGreater(path_m(tf), 2 * path_m(ts))
        # A level the scenario lacks is made; a key the schema lacks is the parser's error.
        rilbed.run(CONVOY, seed=1, duration_s=2, overrides={"convoy.standoff_m": 0.1})
        with self.assertRaisesRegex(rilbed.RunError, "convoy.standof_m|standof_m"):
            rilbed.run(CONVOY, seed=1, duration_s=2, overrides={"convoy.standof_m": 0.1})
        with self.assertRaisesRegex(rilbed.RunError, r"override 'robots.5.kind': '5' is not an index of its list"):
            rilbed.run(CONVOY, seed=1, duration_s=2, overrides={"robots.5.kind": "virtual"})

    def test_errors_a_script_sees(self):
        with self.assertRaisesRegex(rilbed.RunError, "no_such.yaml"):
            rilbed.run(os.path.join(self.tmp, "no_such.yaml"))
        with self.assertRaisesRegex(TypeError, "unexpected option 'speed'"):
            rilbed.run(CONVOY, speed=2)
        with self.assertRaisesRegex(rilbed.RunError, r"faulty.py: RaisesAtTwoSeconds raised an error:(.|\n)*ZeroDivisionError"):
            rilbed.run(self.faulty("RaisesAtTwoSeconds"), seed=1)
        summary = rilbed.run(self.faulty("RaisesAtTwoSeconds"), seed=1, on_controller_error="stop-robot")
        self.assertEqual(summary["controller_failed"], [2])

    def test_what_rilbed_ships_beside_its_binary_is_found_from_python(self):
        # A shipped robot model named bare, and the C controller built into plugins/:
        # both found beside the build's binary, not beside python3.
        d = wander_dict(duration_s=2)
        d["robots"][0]["model"] = "epuck"
        d["robots"][0]["controller"] = "c:braitenberg"
        d["robots"][0].pop("sensors")
        summary = rilbed.run(d, seed=1)
        self.assertEqual(summary["simulated_s"], 2.0)
        self.assertTrue(os.path.exists(os.environ["RILBED_BINARY"]))

    def test_a_malformed_run_folder_is_named_with_its_line(self):
        out = os.path.join(self.tmp, "bad")
        rilbed.run(CONVOY, seed=1, duration_s=1, out=out)
        with open(os.path.join(out, "trajectories.csv"), "a") as f:
            f.write("1.0,2,0.5\n")
        with self.assertRaisesRegex(ValueError, r"trajectories.csv:\d+: 3 fields, not 6"):
            rilbed.read_run(out)

    def faulty(self, cls):
        d = wander_dict(duration_s=4)
        d["robots"][0]["controller"] = {"python": os.path.join(ROOT, "tests", "python", "controllers", "faulty.py"), "class": cls}
        return d


class ControllerApi(unittest.TestCase):
    def test_the_constants_and_the_twist_are_the_cpp_ones(self):
        self.assertEqual(rilbed.MAX_WHEEL_UNITS, 127)
        self.assertEqual(rilbed.PROXIMITY_COUNT, 8)
        self.assertEqual(rilbed.wheels_from_twist(0.08, 0.0), (10, 10))
        self.assertEqual(rilbed.wheels_from_twist(5.0, 0.0), (127, 127))
        o = rilbed.Output(3, -4, behaviour="turn")
        self.assertEqual((o.left, o.right, o.behaviour), (3, -4, "turn"))
        self.assertFalse(rilbed._IN_RUN)


if __name__ == "__main__":
    unittest.main()


class TrackFeaturesFromPython(unittest.TestCase):
    """The track sensor row's reading and the turn on a node, as track_explore uses them."""

    def row(self, count=5, spacing_m=0.012):
        return [rilbed.TrackSensorConfig(mount_x_m=0.02, mount_y_m=(0.5 * (count - 1) - k) * spacing_m, inclination_deg=0)
                for k in range(count)]

    def test_the_row_reads_as_in_cpp(self):
        array = rilbed.TrackArray.of(self.row())
        self.assertEqual(len(array.points_m), 5)
        self.assertAlmostEqual(array.points_m[0][1], 0.024, places=6)
        self.assertEqual(array.centre_element(), 2)
        config = rilbed.TrackReadingConfig(tape_width_m=0.02)
        sides = rilbed.arm_sides(array, config)
        self.assertEqual(sides, [1, 0, 0, 0, -1])
        # The tape under the two left-middle elements, and an arm on the far right.
        r = rilbed.read_track_array(array, [0, 255, 255, 0, 255], config, sides)
        self.assertTrue(r.on_track)
        self.assertEqual(r.elements_on, 3)
        self.assertTrue(r.arm_right)
        self.assertFalse(r.arm_left)
        self.assertAlmostEqual(r.run_offset_m, 0.006, places=6)
        self.assertFalse(rilbed.read_track_array(array, [0] * 5, config, sides).on_track)

    def test_a_cone_that_misses_the_floor_is_refused(self):
        with self.assertRaises(ValueError):
            rilbed.TrackArray.of([rilbed.TrackSensorConfig(inclination_deg=85, cone_angle_deg=30)])

    def test_a_turn_on_an_end_tells_an_end(self):
        # Readings as an end of tape behind the robot gives them: the elements see it while
        # they point backwards (their directions within 20 degrees of straight behind).
        import math
        array = rilbed.TrackArray.of(self.row())
        scan = rilbed.BranchScan(array, rilbed.TrackReadingConfig())
        scan.start(rilbed.Pose(0.5, 0.5, 0.0), 0.0)
        step = 0
        while not scan.complete():
            heading = math.radians(4.0 * step)
            pose = rilbed.Pose(0.5, 0.5, math.atan2(math.sin(heading), math.cos(heading)))
            track = []
            for x, y in array.points_m:
                bearing = heading + math.atan2(y, x)
                behind = abs(math.atan2(math.sin(bearing - math.pi), math.cos(bearing - math.pi)))
                track.append(255 if behind < math.radians(20) else 0)
            scan.add(pose, track)
            step += 1
        result = scan.result()
        self.assertEqual(result.kind, rilbed.TrackFeatureKind.END)
        self.assertEqual(rilbed.track_feature_name(result.kind), "end")
        self.assertEqual(len(result.ways_rad), 1)
        self.assertAlmostEqual(abs(result.ways_rad[0]), math.pi, delta=math.radians(3))
