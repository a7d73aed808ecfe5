"""What the rostests that replay a real log through ekf_slam_node share.

A test derives from ReplayTest and is started by main(), which reads
--bag, --seconds and --rate (and the test's own options) into the class's
`args`. ReplayTest skips a test whose log is absent (the datasets live
beside the project, in ../shared/datasets), waits for the simulated clock
and the node, plays the log with `rosbag play --clock` (its static
transforms latched on /tf_static first, as offline.launch does), and keeps
what /diagnostics said (see Diagnostics).
"""
import argparse
import os
import subprocess
import sys
import threading
import time
import unittest

import rosbag
import rosgraph
import rospy
import rostest
import tf2_ros
from diagnostic_msgs.msg import DiagnosticArray

from ekf_slam_tools.static_tf import static_transforms


class Diagnostics:
    """/diagnostics as it arrives: the wall time of each message, and the
    level, message and values of the last status of each ekf_slam_node
    (named "<node>: EKF-SLAM"; <node> is "upright/upright" for a node
    named upright in namespace upright)."""

    def __init__(self):
        self._lock = threading.Lock()
        self._walls = []
        self._statuses = {}  # name -> (level, message, {key: value})
        rospy.Subscriber("/diagnostics", DiagnosticArray, self._on_message, queue_size=100)

    def _on_message(self, msg):
        with self._lock:
            self._walls.append(time.time())
            for s in msg.status:
                if s.name.endswith(": EKF-SLAM"):
                    self._statuses[s.name] = (s.level, s.message,
                                              {kv.key: kv.value for kv in s.values})

    def walls(self):
        with self._lock:
            return list(self._walls)

    def status(self, prefix=""):
        """(level, message, values) of the node whose name starts with
        prefix ("upright/" for the one in namespace upright), or None."""
        with self._lock:
            for name, status in self._statuses.items():
                if name.startswith(prefix):
                    return status
        return None

    def values(self, prefix=""):
        status = self.status(prefix)
        return dict(status[2]) if status else {}

    def count(self, key, prefix=""):
        return int(self.values(prefix).get(key, 0))

    def drops(self, prefix="", kind="dropped: "):
        """{reason: count} of the non-zero `dropped: <reason>` counters
        (kind="dropped tf: " for the transforms refused)."""
        return {k[len(kind):]: int(v) for k, v in self.values(prefix).items()
                if k.startswith(kind) and int(v) > 0}


class ReplayTest(unittest.TestCase):
    args = None
    _static_broadcaster = None

    def setUp(self):
        if not os.path.exists(self.args.bag):
            self.skipTest(self.args.bag + " not found (the datasets live in ../shared/datasets)")
        self.diagnostics = Diagnostics()

    def wait_for_node(self, service="ekf_slam/reset"):
        """Until /use_sim_time is set and the node offers `service`."""
        deadline = time.time() + 30.0
        while rospy.get_param("/use_sim_time", False) is not True and time.time() < deadline:
            time.sleep(0.1)
        rospy.wait_for_service(service, timeout=60.0)
        time.sleep(1.0)  # the node's subscriptions are connected

    def latch_static_transforms(self, bag, timeout=10.0):
        """Latches the static transforms of `bag` on /tf_static and waits
        (up to `timeout` s) until every subscriber of /tf_static is connected
        to them. rosbag play sends a /tf_static recorded without the latching
        flag once, 0.2 s after it advertises: a node whose connection to the
        player is slower than that (a sandboxed or loaded machine) never
        learns the laser's mount and drops every scan."""
        transforms = static_transforms(bag)
        if not transforms:
            return
        if ReplayTest._static_broadcaster is None:
            ReplayTest._static_broadcaster = tf2_ros.StaticTransformBroadcaster()
        ReplayTest._static_broadcaster.sendTransform(transforms)
        master = rosgraph.Master(rospy.get_name())
        deadline = time.time() + timeout
        while time.time() < deadline:
            subscribers = [n for topic, nodes in master.getSystemState()[1]
                           if topic == "/tf_static" for n in nodes]
            if ReplayTest._static_broadcaster.pub_tf.get_num_connections() >= len(subscribers):
                return
            time.sleep(0.1)

    def player(self, bag=None, seconds=None):
        """`rosbag play --clock` of the first `seconds` (args.seconds) of
        `bag` (args.bag) at args.rate, started: a subprocess.Popen. The
        bag's static transforms are latched first."""
        self.latch_static_transforms(bag or self.args.bag)
        seconds = self.args.seconds if seconds is None else seconds
        # A queue of 1,000 per topic: on a loaded machine rosbag play would
        # otherwise drop messages a subscriber has not read yet (its default
        # is 100), before the node could see or count them.
        # --delay: after advertising, the player waits 2 s (not its 0.2 s)
        # for the subscribers to connect; on a sandboxed machine the node
        # otherwise missed the first scans.
        command = ["rosbag", "play", "--clock", "--quiet", "--queue=1000", "--delay=2", "-r",
                   str(self.args.rate)]
        if seconds > 0:
            command += ["-u", str(seconds)]
        return subprocess.Popen(command + [bag or self.args.bag])

    def play(self, bag=None, seconds=None):
        """Plays as player() does, to the end."""
        self.assertEqual(self.player(bag, seconds).wait(), 0, "rosbag play failed")

    @staticmethod
    def settle(count, period=2.0, first=60.0):
        """Waits until count() stops changing for `period` s (wall): the
        node has worked off its queue. While count() is 0 it waits up to
        `first` s for the first (a loaded machine may be that slow)."""
        deadline = time.time() + first
        while count() == 0 and time.time() < deadline:
            time.sleep(0.5)
        last = -1
        while count() != last:
            last = count()
            time.sleep(period)

    def played_scans(self, topic="/scan"):
        """How many messages of `topic` play() plays: those recorded up to
        args.seconds after the log's start."""
        with rosbag.Bag(self.args.bag) as bag:
            end = bag.get_start_time() + self.args.seconds
            return sum(1 for _, _, t in bag.read_messages(topics=[topic]) if t.to_sec() <= end)


def main(test_class, name, seconds, rate, add_arguments=None):
    """Reads the arguments (defaults `seconds` and `rate`; add_arguments(parser)
    adds a test's own) into test_class.args, and runs the test as rostest
    `name`."""
    parser = argparse.ArgumentParser()
    parser.add_argument("--bag", required=True)
    parser.add_argument("--seconds", type=float, default=seconds)
    parser.add_argument("--rate", type=float, default=rate)
    if add_arguments:
        add_arguments(parser)
    test_class.args, _ = parser.parse_known_args(rospy.myargv(sys.argv)[1:])
    rospy.init_node(name + "_test")
    rostest.rosrun("ekf_slam", name, test_class)
