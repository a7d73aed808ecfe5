#!/usr/bin/python3
"""A package built on ekf_slam the way a user's would be (test/consumer).

In a clean environment that sources only ekf_slam's development space, a
fresh catkin workspace holding test/consumer is built with catkin_make, and
its program runs the core's SlamPipeline on synthetic scans and reads its
landmark map file back. Everything the program needs (the core's headers,
its static libraries in link order, Eigen, yaml-cpp) must come from
`find_package(catkin REQUIRED COMPONENTS ekf_slam)`; a failed build or run
fails the test.
test/install_space_test.py does the same against the install space.
"""
import os
import shutil
import subprocess
import unittest

import rospy
import rostest

CONSUMER_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "consumer")


def clean_env(home_dir):
    """An environment with nothing of a sourced workspace in it."""
    return {"HOME": os.environ.get("HOME", "/tmp"), "PATH": "/usr/bin:/bin", "LANG": "C.UTF-8",
            "ROS_HOME": os.path.join(home_dir, "ros_home")}


def build_and_run_consumer(setup_bash, workspace, timeout=600):
    """Builds test/consumer in a fresh catkin workspace `workspace` on top of
    the space whose setup.bash is `setup_bash`, then runs its program.
    Returns (ok, text): text holds the build's tail or the program's output."""
    shutil.rmtree(workspace, ignore_errors=True)
    os.makedirs(os.path.join(workspace, "src"))
    os.symlink(CONSUMER_DIR, os.path.join(workspace, "src", "consumer"))
    env = clean_env(workspace)
    # One job: the rostests beside this one drive a simulated robot in real time.
    build = subprocess.run(
        ["bash", "-c", "source '%s' && cd '%s' && catkin_make -j1 -DPYTHON_EXECUTABLE=/usr/bin/python3"
         % (setup_bash, workspace)],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
        universal_newlines=True, timeout=timeout)
    if build.returncode != 0:
        return False, "building the consumer failed (%d):\n%s" % (build.returncode, build.stdout[-4000:])
    program = os.path.join(workspace, "devel", "lib", "ekf_slam_consumer", "ekf_slam_consumer")
    run = subprocess.run(
        ["bash", "-c", "source '%s/devel/setup.bash' && '%s'" % (workspace, program)],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
        universal_newlines=True, timeout=120)
    if run.returncode != 0 or "ekf_slam_consumer: ok" not in run.stdout:
        return False, "the consumer failed (%d):\n%s" % (run.returncode, run.stdout[-4000:])
    return True, run.stdout


class ConsumerPackage(unittest.TestCase):
    def test_builds_and_runs_on_the_development_space(self):
        devel = rospy.get_param("~devel_dir")
        ok, text = build_and_run_consumer(os.path.join(devel, "setup.bash"),
                                          rospy.get_param("~workspace"))
        print(text)
        self.assertTrue(ok, text)


if __name__ == "__main__":
    rospy.init_node("consumer_package_test")
    rostest.rosrun("ekf_slam", "consumer_package", ConsumerPackage)
