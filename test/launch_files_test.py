#!/usr/bin/python3
"""Every launch file parses and documents its arguments (test/launch_files.test).

For each file in launch/, `roslaunch --ros-args FILE` must succeed and list
every argument with its doc= text: none may show as "undocumented". An
argument with a default is optional: roslaunch lists any whose default is
the empty string as "Required", so none may have one (a sentinel such as
"none" says "not used" instead). A bag replay stops at the bag's end only
without rviz, and the simulation and the robot run on the wall clock with
the robot's body on robot_description.
"""
import glob
import os
import subprocess
import unittest
import xml.etree.ElementTree as ElementTree

import roslaunch.config
import roslaunch.xmlloader
import rospkg
import rostest

LAUNCH_DIR = os.path.join(rospkg.RosPack().get_path("ekf_slam"), "launch")


def load(name, *args):
    """The roslaunch configuration of launch/`name` with `args` (name:=value)."""
    config = roslaunch.config.ROSLaunchConfig()
    roslaunch.xmlloader.XmlLoader(resolve_anon=False).load(
        os.path.join(LAUNCH_DIR, name), config, argv=["launch"] + list(args), verbose=False)
    return config


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

    def test_no_argument_with_a_default_is_listed_as_required(self):
        launch_dir = os.path.join(rospkg.RosPack().get_path("ekf_slam"), "launch")
        for path in sorted(glob.glob(os.path.join(launch_dir, "*.launch"))):
            name = os.path.basename(path)
            with_default = [arg.get("name") for arg in ElementTree.parse(path).getroot().iter("arg")
                            if arg.get("default") is not None]
            empty = [arg.get("name") for arg in ElementTree.parse(path).getroot().iter("arg")
                     if arg.get("default") == ""]
            self.assertEqual(empty, [], name + ": empty defaults, listed as required by roslaunch")
            run = subprocess.run(["roslaunch", "--ros-args", path], stdout=subprocess.PIPE,
                                 stderr=subprocess.STDOUT, universal_newlines=True)
            self.assertEqual(run.returncode, 0, name + ": " + run.stdout)
            required = []
            section = None
            for line in run.stdout.splitlines():
                if not line.startswith("  "):
                    section = line
                elif section == "Required Arguments:":
                    required.append(line.split(":")[0].strip())
            self.assertEqual([arg for arg in required if arg in with_default], [],
                             name + " lists arguments with a default as required:\n" + run.stdout)

    def test_a_replay_with_rviz_outlives_the_bag(self):
        for rviz, required in (("true", False), ("false", True)):
            config = load("offline.launch", "bag:=/tmp/run.bag", "replay:=true", "rviz:=" + rviz)
            nodes = {node.name: node for node in config.nodes}
            self.assertEqual(nodes["bag_player"].required, required, "rviz:=" + rviz)
            self.assertIn("--pause", nodes["bag_player"].args)
            self.assertIn("--resume /bag_player/pause_playback", nodes["bag_static_tf"].args)
            self.assertIn("robot_state_publisher", nodes)
            self.assertIn("/robot_description", config.params)
            robot = ElementTree.fromstring(config.params["/robot_description"].value)
            self.assertIsNotNone(robot.find("link[@name='chassis']"))
            self.assertIsNone(robot.find("link[@name='laser']"), "the bag holds the laser mount")
        config = load("offline.launch", "bag:=/tmp/run.bag", "replay:=true", "rviz:=true",
                      "stop_at_end:=true")
        self.assertTrue({n.name: n for n in config.nodes}["bag_player"].required)

    def test_sim_and_robot_run_on_the_wall_clock_with_the_robot_description(self):
        for name in ("sim.launch", "robot.launch"):
            config = load(name)
            self.assertIs(config.params["/use_sim_time"].value, False, name)
            self.assertIn('name="chassis"', config.params["/robot_description"].value, name)
            self.assertIn("robot_state_publisher", [node.name for node in config.nodes], name)


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "launch_files", LaunchFiles)
