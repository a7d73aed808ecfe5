#!/usr/bin/python3
"""calibrate_laser_guided through a real pseudo-terminal on the simulated
robot with a mis-mounted, tilted laser (test/calibrate_guided.test): the
prompts are answered as an operator would, the tool drives the robot itself,
and the calibration file it writes must hold the true mount: yaw within 0.3
degrees, x and y within 1 cm, pitch and roll within 0.2 degrees.

Step 1's heights are what an operator measures with a tape (to the
millimetre) at the objects the beam just grazes, 1 m and 3 m ahead for the
pitch and to the right for the roll: the simulated world has no object
heights, so they come from the true mount's beam."""
import math
import os
import tempfile
import unittest

import rospkg
import rospy
import rostest
import yaml

from ekf_slam_tools.terminal import TerminalProgram


def grazing_heights(mount, bearing, near=1.0, far=3.0):
    """The operator's answer to a step-1 prompt: the heights (to the mm) at
    which the mount's beam at `bearing` passes objects `near` and `far`
    metres away over the floor, and their distance (to the cm)."""
    roll, pitch = mount.get("roll", 0.0), mount.get("pitch", 0.0)
    c, s = math.cos(bearing), math.sin(bearing)
    # The beam's direction, rotated by pitch about y after roll about x.
    x = c * math.cos(pitch) + s * math.sin(roll) * math.sin(pitch)
    y = s * math.cos(roll)
    z = -c * math.sin(pitch) + s * math.sin(roll) * math.cos(pitch)
    climb = z / math.hypot(x, y)  # metres up per metre over the floor
    heights = [mount["z"] + d * climb for d in (near, far)]
    return "%.3f %.3f %.2f" % (heights[0], heights[1], far - near)


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
            self.assertTrue(tool.wait_for_text("pitch, two objects straight ahead", 30.0),
                            tool.text())
            tool.type(grazing_heights(truth, 0.0) + "\n")
            self.assertTrue(tool.wait_for_text("l (left) or r (right)", 10.0), tool.text())
            tool.type("r\n")
            self.assertTrue(tool.wait_for_text("roll, right", 10.0), tool.text())
            tool.type(grazing_heights(truth, -math.pi / 2.0) + "\n")
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
        self.assertLess(abs(result["pitch"] - truth["pitch"]), math.radians(0.2), result)
        self.assertLess(abs(result["roll"] - truth["roll"]), math.radians(0.2), result)
        self.assertIn("the front is tipped up", text)


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "calibrate_guided", CalibrateGuided)
