#!/usr/bin/python3
"""Every enabled display of the shipped rviz configurations gets what it
draws (test/rviz_displays.test), checked without rviz:

1. A bag replay (offline.launch replay:=true, the first minutes of ACES at
   10x) against config/rviz/robot.rviz. Skipped with a message when
   ../shared/datasets is absent.
2. Then, on the same roscore with use_sim_time still true as the replay
   left it, sim.launch with a waypoint loop against config/rviz/sim.rviz:
   sim.launch must set use_sim_time false so that the drivers start, the
   robot drives and SLAM publishes poses.

For each enabled display of a configuration: each topic ("Topic", "Marker
Topic") delivers a message whose header frame resolves in tf into the fixed
frame at the message's stamp (as rviz looks it up); each frame a display
names (Axes, Grid "Reference Frame", the TF display's frames) resolves;
robot_description is set and every link of it resolves; for a TF display,
every frame on tf resolves (rviz warns about any other). A topic that is
empty until a service call must be disabled in the configuration.
"""
import os
import signal
import subprocess
import sys
import threading
import time
import unittest
import xml.etree.ElementTree as ElementTree

import rospkg
import rospy
import rostest
import rostopic
import tf2_ros
import yaml
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import Odometry

PACKAGE = rospkg.RosPack().get_path("ekf_slam")


def enabled_displays(displays):
    """The enabled displays of an rviz Displays list, groups flattened."""
    for display in displays or []:
        if not display.get("Enabled", False):
            continue
        if display.get("Class") == "rviz/Group":
            yield from enabled_displays(display.get("Displays"))
        else:
            yield display


def load_config(name):
    with open(os.path.join(PACKAGE, "config", "rviz", name)) as stream:
        config = yaml.safe_load(stream)
    manager = config["Visualization Manager"]
    return manager["Global Options"]["Fixed Frame"], list(enabled_displays(manager["Displays"]))


class TopicWatch:
    """The newest few messages of a topic of any type, from its first publisher."""

    def __init__(self, topic):
        self.topic = topic
        self.messages = []
        self.lock = threading.Lock()
        self.subscriber = None

    def poll(self):
        if self.subscriber is None:
            cls, real_topic, _ = rostopic.get_topic_class(self.topic, blocking=False)
            if cls is not None:
                self.subscriber = rospy.Subscriber(real_topic, cls, self.callback, queue_size=20)

    def callback(self, message):
        with self.lock:
            self.messages = (self.messages + [message])[-20:]

    def take(self):
        with self.lock:
            taken, self.messages = self.messages, []
        return taken

    def close(self):
        if self.subscriber is not None:
            self.subscriber.unregister()


def frames_of(message):
    """(frame, stamp) pairs a display transforms for `message`."""
    if hasattr(message, "markers"):
        return [(m.header.frame_id, m.header.stamp) for m in message.markers if m.action in (0, 1)]
    return [(message.header.frame_id, message.header.stamp)]


class RvizDisplays(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.buffer = tf2_ros.Buffer(cache_time=rospy.Duration(3600.0))
        cls.listener = tf2_ros.TransformListener(cls.buffer)
        cls.launches = []

    @classmethod
    def tearDownClass(cls):
        for launch in cls.launches:
            cls.stop(launch)

    @staticmethod
    def stop(launch):
        if launch.poll() is None:
            launch.send_signal(signal.SIGINT)
            try:
                launch.wait(40)
            except subprocess.TimeoutExpired:
                launch.kill()
                launch.wait()

    def roslaunch(self, name, *args):
        log = open(os.path.join(os.environ.get("ROS_HOME", "/tmp"), "rviz_displays_%s.log" % name), "w")
        launch = subprocess.Popen(["roslaunch", "ekf_slam", name] + list(args), stdout=log,
                                  stderr=subprocess.STDOUT)
        self.launches.append(launch)
        return launch

    def resolves(self, fixed, frame, stamp):
        if not frame:
            return False, "empty frame_id"
        try:
            self.buffer.lookup_transform(fixed, frame.lstrip("/"), stamp, rospy.Duration(1.0))
            return True, ""
        except tf2_ros.TransformException as error:
            return False, str(error)

    def check_config(self, name, within):
        """Waits up to `within` s (wall clock) for every enabled display of
        config/rviz/`name` to have what it needs; fails naming those without."""
        fixed, displays = load_config(name)
        watches, frames, problems = {}, {}, []
        description_links, tf_display = None, False
        for display in displays:
            label = "%s '%s'" % (display["Class"], display["Name"])
            for key in ("Topic", "Marker Topic"):
                if display.get(key):
                    watches[display[key]] = (label, TopicWatch(display[key]))
            reference = display.get("Reference Frame")
            if reference and reference != "<Fixed Frame>":
                frames[reference] = label
            if display["Class"] == "rviz/TF":
                tf_display = True
                for frame, value in (display.get("Frames") or {}).items():
                    if isinstance(value, dict) and value.get("Value"):
                        frames[frame] = label
            if display["Class"] == "rviz/RobotModel":
                description_links = display.get("Robot Description", "robot_description")
        print("%s: fixed frame %s, %d enabled displays, topics %s" %
              (name, fixed, len(displays), ", ".join(sorted(watches))))
        if "/smoothed_path" in watches:
            problems.append("%s on /smoothed_path: empty until ~smooth, must be disabled" %
                            watches.pop("/smoothed_path")[0])

        deadline = time.time() + within
        pending = dict(watches)
        last_error = {}
        while pending and time.time() < deadline and not rospy.is_shutdown():
            for topic, (label, watch) in list(pending.items()):
                watch.poll()
                for message in reversed(watch.take()):
                    pairs = frames_of(message)
                    if not pairs:
                        last_error[topic] = "a message without anything to draw"
                        continue
                    results = [self.resolves(fixed, f, s) for f, s in pairs]
                    failed = [e for ok, e in results if not ok]
                    if not failed:
                        print("%s: %s ok (%s at %.2f)" % (name, topic, pairs[0][0], pairs[0][1].to_sec()))
                        del pending[topic]
                        break
                    last_error[topic] = failed[0]
            time.sleep(0.2)
        for label, watch in watches.values():
            watch.close()
        for topic, (label, watch) in pending.items():
            problems.append("%s on %s: %s" % (label, topic, last_error.get(
                topic, "no message within %.0f s" % within) if watch.subscriber or topic in last_error
                else "never published"))

        for frame, label in frames.items():
            ok, error = self.resolves(fixed, frame, rospy.Time(0))
            if not ok:
                problems.append("%s: frame %s: %s" % (label, frame, error))
        if description_links is not None:
            if not rospy.has_param(description_links):
                problems.append("RobotModel: no parameter " + description_links)
            else:
                robot = ElementTree.fromstring(rospy.get_param(description_links))
                links = [link.get("name") for link in robot.findall("link")]
                for link in links:
                    ok, error = self.resolves(fixed, link, rospy.Time(0))
                    if not ok:
                        problems.append("RobotModel: link %s: %s" % (link, error))
                print("%s: robot_description: %d links" % (name, len(links)))
        if tf_display:
            known = yaml.safe_load(self.buffer.all_frames_as_yaml()) or {}
            for frame in sorted(known):
                ok, error = self.resolves(fixed, frame, rospy.Time(0))
                if not ok:
                    problems.append("TF display: frame %s: %s" % (frame, error))
        self.assertEqual(problems, [], name + ":\n  " + "\n  ".join(problems))

    def test_1_bag_replay_feeds_robot_rviz(self):
        bag = os.path.join(PACKAGE, "..", "shared", "datasets", "aces.orig.bag")
        if not os.path.exists(bag):
            self.skipTest("%s is absent: the bag replay is not checked" % os.path.normpath(bag))
        launch = self.roslaunch("offline.launch", "bag:=" + os.path.realpath(bag), "replay:=true",
                                "rate:=10", "stop_at_end:=false")
        try:
            self.check_config("robot.rviz", within=90.0)
            # The bag's mount reached a subscriber that came after the bag
            # started: it is latched.
            late = tf2_ros.Buffer()
            _listener = tf2_ros.TransformListener(late)
            late.lookup_transform("base_link", "laser", rospy.Time(0), rospy.Duration(5.0))
            del _listener
        finally:
            self.stop(launch)

    def test_2_sim_after_a_replay_drives_and_feeds_sim_rviz(self):
        # What a replay leaves on the parameter server.
        rospy.set_param("/use_sim_time", True)
        link_dir = "/tmp/ekf_slam_sim_rostest_rviz_displays_%d" % os.getpid()
        launch = self.roslaunch("sim.launch", "waypoints:=office_loop", "link_dir:=" + link_dir)
        try:
            poses = []
            rospy.Subscriber("pose", PoseWithCovarianceStamped, poses.append)
            first = rospy.wait_for_message("ground_truth/odom", Odometry, timeout=60.0).pose.pose.position
            self.assertFalse(rospy.get_param("/use_sim_time"), "sim.launch must set use_sim_time false")
            self.check_config("sim.rviz", within=60.0)
            moved = 0.0
            deadline = time.time() + 30.0
            while moved < 1.0 and time.time() < deadline:
                now = rospy.wait_for_message("ground_truth/odom", Odometry, timeout=10.0).pose.pose.position
                moved = ((now.x - first.x) ** 2 + (now.y - first.y) ** 2) ** 0.5
            self.assertGreater(moved, 1.0, "the robot did not drive")
            self.assertGreater(len(poses), 20, "SLAM published %d poses" % len(poses))
            self.assertIsNone(launch.poll(), "sim.launch ended")
        finally:
            self.stop(launch)


if __name__ == "__main__":
    rospy.init_node("rviz_displays_test")
    rostest.rosrun("ekf_slam", "rviz_displays", RvizDisplays, sys.argv)
