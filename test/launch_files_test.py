#!/usr/bin/python3
"""Every launch file parses and documents its arguments (test/launch_files.test).

For each file in launch/, `roslaunch --ros-args FILE` must succeed and list
every argument with its doc= text: none may show as "undocumented".
"""
import glob
import os
import subprocess
import unittest

import rospkg
import rostest


class LaunchFiles(unittest.TestCase):
    def test_every_argument_is_documented(self):
        launch_dir = os.path.join(rospkg.RosPack().get_path("ekf_slam"), "launch")
        files = sorted(glob.glob(os.path.join(launch_dir, "*.launch")))
        self.assertGreater(len(files), 4, "launch files not found in " + launch_dir)
        for path in files:
            run = subprocess.run(["roslaunch", "--ros-args", path], stdout=subprocess.PIPE,
                                 stderr=subprocess.STDOUT, universal_newlines=True)
            name = os.path.basename(path)
            self.assertEqual(run.returncode, 0, name + ": " + run.stdout)
            listed = [line for line in run.stdout.splitlines() if line.startswith("  ")]
            self.assertTrue(listed, name + " lists no argument")
            for line in listed:
                self.assertNotIn("undocumented", line, name)
                self.assertRegex(line, r"^  \w+( \(default [^)]*\))?: \S", name + ": " + line)


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "launch_files", LaunchFiles)
