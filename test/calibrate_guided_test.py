#!/usr/bin/python3
"""calibrate_laser_guided through a real pseudo-terminal on the simulated
robot with a mis-mounted laser (test/calibrate_guided.test): the prompts are
answered as an operator would (no pitch or roll, then go), the tool drives
the robot itself, and the calibration file it writes must hold the true
mount: yaw within 0.3 degrees, x and y within 1 cm."""
import math
import os
import tempfile
import unittest

import rospkg
import rospy
import rostest
import yaml

from ekf_slam_tools.terminal import TerminalProgram


class CalibrateGuided(unittest.TestCase):
    def test_recovers_the_mount(self):
        rospy.init_node("calibrate_guided_test")
        with open(rospy.get_param("~truth")) as stream:
            truth = yaml.safe_load(stream)
        out = os.path.join(tempfile.mkdtemp(prefix="calibrate_guided_"), "calibration.yaml")
        nominal = os.path.join(rospkg.RosPack().get_path("ekf_slam"), "config", "calibration.yaml")
        rospy.wait_for_message("scan", rospy.AnyMsg, timeout=60.0)
        rospy.wait_for_message("odom", rospy.AnyMsg, timeout=30.0)
        tool = TerminalProgram(["rosrun", "ekf_slam", "calibrate_laser_guided",
                                "_calibration:=" + nominal, "_write:=" + out])
        try:
            self.assertTrue(tool.wait_for_text("pitch: heights", 30.0), tool.text())
            tool.type("\n")  # no pitch measurement
            self.assertTrue(tool.wait_for_text("roll: heights", 10.0), tool.text())
            tool.type("\n")
            self.assertTrue(tool.wait_for_text("Enter to go on", 20.0), tool.text())
            tool.type("\n")
            self.assertTrue(tool.wait_for_text("written to", 150.0), tool.text())
            self.assertEqual(tool.wait(), 0, tool.text())
            text = tool.text()
        finally:
            tool.kill()
        rospy.loginfo("calibrate_laser_guided said:\n%s", text)
        with open(out) as stream:
            result = yaml.safe_load(stream)
        self.assertLess(abs(result["yaw"] - truth["yaw"]), math.radians(0.3), result)
        self.assertLess(abs(result["x"] - truth["x"]), 0.01, result)
        self.assertLess(abs(result["y"] - truth["y"]), 0.01, result)
        self.assertEqual(result["child_frame"], "laser")


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "calibrate_guided", CalibrateGuided)
