#!/usr/bin/python3
"""Replays a log through the live node faster than real time and reports
whether it keeps up.

Starts its own roscore (port --port) with use_sim_time, slam.launch pinned to
one core (taskset -c --core), and `rosbag play --clock -r RATE`. Measures
on the wall clock:
- per-scan processing time, as the node measures it (/diagnostics, over
  the whole run): the pipeline (features, scan matching, filter; the back
  end runs on its own thread) and the publication;
- per-scan latency: from the scan's arrival on /scan to the arrival of the
  pose the node publishes for it (same stamp): the processing and the wait
  for the scan's transforms (a log whose odometry pauses while the robot
  stands holds its scans until the next odometry sample);
- how far the back end lags: the largest backlog of scans handed to it and
  not processed yet, sampled on /diagnostics once a second;
- the largest gap between two map -> odom transforms on /tf;
- the map thread: grids published, and the last build time (/diagnostics);
- scans the node dropped (every "dropped: ..." counter) and scans it never
  answered: counted from /scan and /pose as `rosbag record` (C++) saw them.
  This Python probe itself misses a few messages of a 5x replay, so its
  own counts would blame the node for them.

usage (after make build, with the workspace sourced):
  source .build/setup.bash
  tools/dev/realtime_replay.py [--bag ../shared/datasets/intel.orig.bag] [--rate 5] [--core 0]
"""
import argparse
import math
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import rosbag
import rospy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseWithCovarianceStamped
from sensor_msgs.msg import LaserScan
from tf2_msgs.msg import TFMessage


def percentile(values, p):
    if not values:
        return float("nan")
    s = sorted(values)
    k = min(len(s) - 1, max(0, int(math.ceil(p / 100.0 * len(s))) - 1))
    return s[k]


class Probe:
    def __init__(self):
        self.scan_wall = {}  # stamp (ns) -> wall time of arrival
        self.latency = []  # s
        self.tf_wall = []
        self.drops = {}
        self.maps = 0
        self.map_build = float("nan")
        self.scans = 0
        self.backlog = 0
        self.processing = {}  # "p50" / "p99" / "max" -> ms
        rospy.Subscriber("scan", LaserScan, self.on_scan, queue_size=10000)
        rospy.Subscriber("pose", PoseWithCovarianceStamped, self.on_pose, queue_size=10000)
        rospy.Subscriber("/tf", TFMessage, self.on_tf, queue_size=10000)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=100)

    def on_scan(self, msg):
        self.scans += 1
        self.scan_wall[msg.header.stamp.to_nsec()] = time.monotonic()

    def on_pose(self, msg):
        sent = self.scan_wall.pop(msg.header.stamp.to_nsec(), None)
        if sent is not None:
            self.latency.append(time.monotonic() - sent)

    def on_tf(self, msg):
        for t in msg.transforms:
            if t.header.frame_id == "map" and t.child_frame_id == "odom":
                self.tf_wall.append(time.monotonic())

    def on_diagnostics(self, msg):
        for status in msg.status:
            for kv in status.values:
                if kv.key.startswith("dropped: ") and kv.key != "dropped: paused":
                    self.drops[kv.key] = int(float(kv.value))
                elif kv.key == "maps published":
                    self.maps = int(float(kv.value))
                elif kv.key == "last map build [s]":
                    self.map_build = float(kv.value)
                elif kv.key.startswith("processing time "):
                    self.processing[kv.key.split()[2]] = float(kv.value)
                elif kv.key == "back-end backlog (scans)":
                    self.backlog = max(self.backlog, int(float(kv.value)))


def main():
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bag", default=os.path.join(root, "..", "shared", "datasets",
                                                      "intel.orig.bag"))
    parser.add_argument("--rate", type=float, default=5.0)
    parser.add_argument("--core", type=int, default=0)
    parser.add_argument("--port", type=int, default=11472)
    parser.add_argument("--seconds", type=float, default=0.0, help="play only this much (0: all)")
    args = parser.parse_args()
    if not os.path.exists(args.bag):
        sys.exit("realtime_replay: %s not found" % args.bag)

    env = dict(os.environ, ROS_MASTER_URI="http://localhost:%d" % args.port)
    os.environ.update(env)
    procs = [subprocess.Popen(["roscore", "-p", str(args.port)], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                              preexec_fn=os.setsid)]
    try:
        time.sleep(3.0)
        subprocess.check_call(["rosparam", "set", "use_sim_time", "true"], env=env)
        record_dir = tempfile.mkdtemp(prefix="realtime_replay_")
        # As the replay rostests run it: the node's tf buffer widened by the
        # rate (10 s of log is 2 s of wall clock at 5x).
        launch = os.path.join(record_dir, "replay.launch")
        with open(launch, "w") as f:
            f.write('<launch>\n  <include file="$(find ekf_slam)/launch/slam.launch">\n'
                    '    <arg name="features" value="false"/>\n  </include>\n'
                    '  <param name="ekf_slam/tf_cache_time" value="%g"/>\n</launch>\n'
                    % (10.0 * args.rate))
        procs.append(subprocess.Popen(
            ["taskset", "-c", str(args.core), "roslaunch", launch], env=env,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, preexec_fn=os.setsid))
        rospy.init_node("realtime_replay", disable_signals=True)
        probe = Probe()
        answers = os.path.join(record_dir, "answers.bag")
        procs.append(subprocess.Popen(
            ["rosbag", "record", "-O", answers, "/scan", "/pose",
             "__name:=realtime_replay_record"], env=env, stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL, preexec_fn=os.setsid))
        time.sleep(5.0)
        # The log's static transforms (base_link -> laser), latched, as
        # offline.launch gives them: the player waits, paused, until they are.
        procs.append(subprocess.Popen(
            ["rosrun", "ekf_slam", "bag_static_tf.py", args.bag, "--resume",
             "/realtime_replay_player/pause_playback"], env=env, stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL, preexec_fn=os.setsid))
        play = ["rosbag", "play", "--clock", "--quiet", "--pause", "-r", str(args.rate), args.bag,
                "__name:=realtime_replay_player"]
        if args.seconds > 0:
            play += ["-u", str(args.seconds)]
        start = time.monotonic()
        subprocess.check_call(play, env=env)
        played = time.monotonic() - start
        time.sleep(5.0)  # the last scans and diagnostics
        subprocess.call(["rosnode", "kill", "/realtime_replay_record"], env=env,
                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(2.0)
        scans, posed = [], set()
        with rosbag.Bag(answers) as bag:
            for topic, msg, _ in bag.read_messages():
                if topic == "/scan":
                    scans.append(msg.header.stamp.to_nsec())
                else:
                    posed.add(msg.header.stamp.to_nsec())
        shutil.rmtree(record_dir, ignore_errors=True)
        unanswered = [stamp for stamp in scans if stamp not in posed]
        gaps = [b - a for a, b in zip(probe.tf_wall, probe.tf_wall[1:])]
        print("log: %s at %gx on core %d: %d scans in %.1f s of wall-clock"
              % (os.path.basename(args.bag), args.rate, args.core, probe.scans, played))
        print("per-scan processing time: p50 %.1f ms, p99 %.1f ms, max %.1f ms"
              % tuple(probe.processing.get(k, float("nan")) for k in ("p50", "p99", "max")))
        print("per-scan latency (scan in -> pose out): p50 %.1f ms, p99 %.1f ms, max %.1f ms"
              " over %d scans" % (1e3 * percentile(probe.latency, 50),
                                  1e3 * percentile(probe.latency, 99),
                                  1e3 * max(probe.latency or [float("nan")]), len(probe.latency)))
        print("largest gap between map -> odom transforms: %.1f ms" % (1e3 * max(gaps or [0])))
        print("back end (own thread): largest backlog %d scans (sampled once a second);"
              " map thread: %d grids, last built in %.2f s"
              % (probe.backlog, probe.maps, probe.map_build))
        dropped = sum(probe.drops.values())
        print("dropped by the node: %d %s; never answered: %d of %d recorded scans%s"
              % (dropped, {k: v for k, v in probe.drops.items() if v}, len(unanswered),
                 len(scans), " (stamps %s)" % ", ".join("%.3f" % (s / 1e9) for s in unanswered[:5])
                 if unanswered else ""))
    finally:
        for p in reversed(procs):
            try:
                os.killpg(p.pid, signal.SIGINT)
                p.wait(timeout=15)
            except Exception:
                os.killpg(p.pid, signal.SIGKILL)


if __name__ == "__main__":
    main()
