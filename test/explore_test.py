#!/usr/bin/python3
"""Unattended exploration of a simulated world (test/explore_office.test):
sim.launch with explore:=true, the simulated drivers, SLAM and the safety
gate in the loop. The explorer must end by itself (~done), back within
0.5 m of its start (ground truth); the final map must cover at least 95 %
of the free space the simulator knows to be reachable from the start; and
the robot must never touch a wall (no stall from the P3-DX driver). The
safety gate's stops, the time and the distance driven are printed, and with
--out written to a YAML file. With --saved BASE (the explorer's save_path)
the map and the SLAM state it saved at the end must be there, written
during the run: BASE.yaml (landmarks), BASE_grid.yaml and .pgm, BASE.state.

With --rooms (the rooms world, ekf_slam_tools.worlds.rooms_layout) the
order in which the robot entered the rooms (ground truth, at least
ROOM_DEPTH inside one) is printed, and no room may be entered twice: the
robot finishes a room before it leaves it. The corridor is passed through
as often as needed.

Reachable free space: the world's free cells connected to the start cell
through free cells (ground_truth/world, in the map frame). Covered: the
cell of /map at the same place is known, free or occupied. Home: the last
true position against the first (the truth arrives from the start, before
the robot moves).
"""
import argparse
import math
import os
import sys
import threading
import time
import unittest
from collections import deque

import rospy
import rostest
import yaml
from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import OccupancyGrid, Odometry
from std_msgs.msg import Bool

from ekf_slam_tools import worlds
from ekf_slam_tools.se2 import compose, inverse, yaw_of

COVERAGE = 0.95
HOME = 0.5  # m
ROOM_DEPTH = 0.4  # m inside a room's walls that counts as in it (not in its door)


class Recorder:
    def __init__(self):
        self.lock = threading.Lock()
        self.truth = []  # (x, y, yaw) in the world
        self.world = None
        self.map = None
        self.done = False
        self.stalled = False
        self.gate = {}
        self.explorer = {}
        self.explorer_message = ""
        rospy.Subscriber("ground_truth/odom", Odometry, self.on_truth, queue_size=200)
        rospy.Subscriber("ground_truth/world", OccupancyGrid, self.on_world, queue_size=1)
        rospy.Subscriber("map", OccupancyGrid, self.on_map, queue_size=1)
        rospy.Subscriber("explorer/done", Bool, self.on_done, queue_size=1)
        rospy.Subscriber("stall", Bool, self.on_stall, queue_size=10)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=50)

    def on_truth(self, message):
        p = message.pose.pose
        with self.lock:
            self.truth.append((p.position.x, p.position.y, yaw_of(p.orientation)))

    def on_world(self, message):
        self.world = message

    def on_map(self, message):
        self.map = message

    def on_done(self, message):
        self.done = self.done or message.data

    def on_stall(self, message):
        self.stalled = self.stalled or message.data

    def on_diagnostics(self, message):
        for status in message.status:
            values = {kv.key: kv.value for kv in status.values}
            if status.name.endswith("safety gate"):
                self.gate = values
            elif status.name.endswith("exploration"):
                self.explorer = values
                self.explorer_message = status.message


def origin_of(grid):
    o = grid.info.origin
    return (o.position.x, o.position.y, yaw_of(o.orientation))


def reachable_free(world):
    """Cells (col, row) of the world grid connected through free cells to
    the one holding the map frame's origin (the robot's start)."""
    info = world.info
    w, h = info.width, info.height
    sx, sy, _ = compose(inverse(origin_of(world)), (0.0, 0.0, 0.0))
    col, row = int(math.floor(sx / info.resolution)), int(math.floor(sy / info.resolution))
    free = [0 <= v < 50 for v in world.data]
    seen = set()
    if not (0 <= col < w and 0 <= row < h) or not free[row * w + col]:
        return seen
    queue = deque([(col, row)])
    seen.add((col, row))
    while queue:
        c, r = queue.popleft()
        for dc, dr in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            n = (c + dc, r + dr)
            if 0 <= n[0] < w and 0 <= n[1] < h and n not in seen and free[n[1] * w + n[0]]:
                seen.add(n)
                queue.append(n)
    return seen


def coverage(world, slam_map):
    """Share of the reachable free world cells that the SLAM map knows (both
    grids in the map frame; the SLAM node's grid is not rotated)."""
    cells = reachable_free(world)
    origin, res = origin_of(world), world.info.resolution
    m = slam_map.info
    known = 0
    for c, r in cells:
        x, y, _ = compose(origin, ((c + 0.5) * res, (r + 0.5) * res, 0.0))
        mc = int(math.floor((x - m.origin.position.x) / m.resolution))
        mr = int(math.floor((y - m.origin.position.y) / m.resolution))
        if 0 <= mc < m.width and 0 <= mr < m.height and slam_map.data[mr * m.width + mc] >= 0:
            known += 1
    return known / max(1, len(cells)), len(cells)


def room_visits(truth, layout):
    """The areas of `layout` (name: (x0, y0, x1, y1)) the path passes
    through, in order, each stay once: a position counts in an area when it
    lies ROOM_DEPTH inside it; between areas (doors) it counts in none."""
    visits = []
    for x, y, _ in truth:
        for name, (x0, y0, x1, y1) in layout.items():
            if x0 + ROOM_DEPTH < x < x1 - ROOM_DEPTH and y0 + ROOM_DEPTH < y < y1 - ROOM_DEPTH:
                if not visits or visits[-1] != name:
                    visits.append(name)
                break
    return visits


class Explore(unittest.TestCase):
    def test_explores_and_returns(self):
        argv = [a for a in sys.argv[1:] if not a.startswith("__") and not a.startswith("--gtest")]
        parser = argparse.ArgumentParser()
        parser.add_argument("--timeout", type=float, default=1200.0)
        parser.add_argument("--out", default="")
        parser.add_argument("--rooms", action="store_true",
                            help="the rooms world: check the order of the rooms")
        parser.add_argument("--saved", default="",
                            help="the explorer's save_path: check what it saved")
        args, _ = parser.parse_known_args(argv)
        rospy.init_node("explore_test")
        r = Recorder()
        started = time.monotonic()
        started_wall = time.time()
        while not rospy.is_shutdown() and not r.done and time.monotonic() - started < args.timeout:
            time.sleep(0.5)
        elapsed = time.monotonic() - started
        time.sleep(1.0)  # the last diagnostics
        self.assertTrue(r.done, "exploration did not end within %.0f s: %s" %
                        (args.timeout, r.explorer_message))
        with r.lock:
            truth = list(r.truth)
        self.assertTrue(truth and r.world is not None and r.map is not None,
                        "no ground truth, world or map received")
        driven = sum(math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in zip(truth, truth[1:]))
        home = math.hypot(truth[-1][0] - truth[0][0], truth[-1][1] - truth[0][1])
        covered, reachable = coverage(r.world, r.map)
        stops = {k[len("stops: "):]: int(v) for k, v in r.gate.items() if k.startswith("stops: ")}
        result = {
            "time_s": round(elapsed, 1),
            "distance_driven_m": round(driven, 1),
            "final_distance_from_start_m": round(home, 3),
            "coverage": round(covered, 4),
            "reachable_free_cells": reachable,
            "safety_gate_stops": stops,
            "stalled": r.stalled,
            "explorer": r.explorer_message,
            "goals_given_up": r.explorer.get("goals given up", "?"),
        }
        if args.rooms:
            visits = room_visits(truth, worlds.rooms_layout())
            result["rooms_entered"] = visits
        print("exploration: %s" % yaml.safe_dump(result, default_flow_style=True).strip())
        if args.out:
            os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
            with open(args.out, "w") as f:
                yaml.safe_dump(result, f, default_flow_style=False)
        if args.saved:
            for suffix in (".yaml", "_grid.yaml", "_grid.pgm", ".state"):
                path = args.saved + suffix
                self.assertTrue(os.path.isfile(path), "the explorer did not save %s" % path)
                self.assertGreaterEqual(os.path.getmtime(path), started_wall - 1.0,
                                        "%s is older than this run" % path)
        self.assertFalse(r.stalled, "the robot touched a wall (the driver reported a stall)")
        self.assertLess(home, HOME, "ended %.2f m from its start" % home)
        self.assertGreaterEqual(covered, COVERAGE, "the map covers %.1f %% of the reachable "
                                "free space" % (100 * covered))
        if args.rooms:
            rooms = [v for v in visits if v != "corridor"]
            twice = sorted({v for v in rooms if rooms.count(v) > 1})
            self.assertFalse(twice, "rooms entered again after being left: %s (order %s)" %
                             (twice, visits))
            self.assertEqual(len(set(rooms)), len(worlds.rooms_layout()) - 1,
                             "not every room entered: %s" % visits)


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "explore", Explore, sys.argv)
