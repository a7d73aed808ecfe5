#!/usr/bin/python3
"""rviz under Xvfb with each shipped config (config/rviz/sim.rviz and
robot.rviz) on the running simulated system (test/rviz_smoke.test):
tools/dev/rviz_screenshot.py must report rviz alive for the whole wait, no error
line from rviz, and a screenshot that is not blank. The SLAM outputs are
awaited first so that the displays have data to draw."""
import os
import subprocess
import sys
import unittest

import rospkg
import rospy
import rostest
from geometry_msgs.msg import PoseWithCovarianceStamped


class RvizSmoke(unittest.TestCase):
    def test_rviz_loads_the_simulation_config_and_draws(self):
        argv = [a for a in sys.argv[1:] if not a.startswith("__") and not a.startswith("--gtest")]
        out = argv[argv.index("--out") + 1] if "--out" in argv else "/tmp/ekf_slam_rviz_smoke.png"
        self.check_config("sim.rviz", out)

    def test_rviz_loads_the_robot_config_and_draws(self):
        self.check_config("robot.rviz", "/tmp/ekf_slam_rviz_smoke_robot.png")

    def check_config(self, name, out):
        rospy.wait_for_message("pose", PoseWithCovarianceStamped, timeout=60.0)
        root = rospkg.RosPack().get_path("ekf_slam")
        if os.path.exists(out):
            os.unlink(out)
        result = subprocess.run(
            ["/usr/bin/python3", os.path.join(root, "tools", "dev", "rviz_screenshot.py"), "--config",
             os.path.join(root, "config", "rviz", name), "--out", out, "--wait", "25"],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, timeout=120)
        print(result.stdout)
        self.assertEqual(result.returncode, 0, result.stdout)
        self.assertTrue(os.path.getsize(out) > 10000, "screenshot too small to hold a picture")
        self.assertIn("ran the whole", result.stdout)
        self.assertIn("0 error line(s)", result.stdout)


if __name__ == "__main__":
    rospy.init_node("rviz_smoke_test")
    rostest.rosrun("ekf_slam", "rviz_smoke", RvizSmoke, sys.argv)
