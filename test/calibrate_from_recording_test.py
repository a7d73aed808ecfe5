#!/usr/bin/python3
"""The automatic laser calibration on a recorded drive
(test/calibrate_from_recording.test): record.launch records the simulated
robot's waypoint loop; calibrate_laser_from_bag on the bag must recover the
mount the simulated laser really has (yaw within 0.5 degrees, x and y
within 2 cm) and write it."""
import glob
import math
import os
import shutil
import signal
import subprocess
import tempfile
import time
import unittest

import rospkg
import rospy
import rostest
import yaml
from std_msgs.msg import Bool


class CalibrateFromRecording(unittest.TestCase):
    def test_recorded_loop_gives_the_mount(self):
        rospy.init_node("calibrate_from_recording_test")
        with open(rospy.get_param("~truth")) as stream:
            truth = yaml.safe_load(stream)
        tmp = tempfile.mkdtemp(prefix="calibrate_recording_")
        self.addCleanup(shutil.rmtree, tmp, True)
        done = []
        rospy.Subscriber("waypoint_driver/done", Bool, lambda m: done.append(m.data), queue_size=5)
        rospy.wait_for_message("scan", rospy.AnyMsg, timeout=60.0)
        record = subprocess.Popen(["roslaunch", "ekf_slam", "record.launch",
                                   "prefix:=" + os.path.join(tmp, "loop")],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            deadline = time.monotonic() + 200.0
            while not (done and done[-1]) and time.monotonic() < deadline:
                time.sleep(0.2)
            self.assertTrue(done and done[-1], "the waypoint loop did not finish")
            time.sleep(1.0)
        finally:
            record.send_signal(signal.SIGINT)
            record.wait(timeout=30)
        bags = glob.glob(os.path.join(tmp, "loop_*.bag"))
        self.assertEqual(len(bags), 1, os.listdir(tmp))
        out = os.path.join(tmp, "calibration.yaml")
        nominal = os.path.join(rospkg.RosPack().get_path("ekf_slam"), "config", "calibration.yaml")
        run = subprocess.run(["rosrun", "ekf_slam", "calibrate_laser_from_bag", "--bag", bags[0],
                              "--calibration", nominal, "--write", out],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                             universal_newlines=True)
        rospy.loginfo("calibrate_laser_from_bag:\n%s", run.stdout)
        self.assertEqual(run.returncode, 0, run.stdout)
        with open(out) as stream:
            result = yaml.safe_load(stream)
        self.assertLess(abs(result["yaw"] - truth["yaw"]), math.radians(0.5), result)
        self.assertLess(abs(result["x"] - truth["x"]), 0.02, result)
        self.assertLess(abs(result["y"] - truth["y"]), 0.02, result)


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "calibrate_from_recording", CalibrateFromRecording)
