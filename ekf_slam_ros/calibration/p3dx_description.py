#!/usr/bin/python3
"""Prints the P3-DX robot description with the laser where calibration.yaml puts it.

    rosrun ekf_slam p3dx_description CALIBRATION_YAML [URDF]
    rosrun ekf_slam p3dx_description --no-laser [URDF]

URDF defaults to config/p3dx.urdf of this package. The joint `laser_joint`
gets the x, y, z, yaw, roll and pitch (0 when absent) of the calibration
file (URDF's rpy: the same rotation yaw · pitch · roll), and its child link the
calibration's child_frame, so that robot_state_publisher broadcasts the one
mount that SLAM and the simulator read: config/calibration.yaml stays the
only place that holds it. Exit status 1, with a message naming the file and
the key, when the calibration is missing, malformed or names a parent frame
other than the description's root.

--no-laser leaves out the laser (laser_joint and its link): for a bag
replay, whose base_link -> laser is the recorded robot's and comes from the
bag, so that robot_state_publisher adds the body without a second,
different mount.
"""
import math
import os
import sys
import xml.etree.ElementTree as ElementTree

import yaml

KEYS = ("parent_frame", "child_frame", "x", "y", "z", "yaw")
OPTIONAL_KEYS = ("roll", "pitch")  # the tilt, 0 when absent


def load_mount(path):
    """The calibration's mount as a dict; raises ValueError naming the problem."""
    try:
        with open(path) as stream:
            data = yaml.safe_load(stream)
    except (OSError, yaml.YAMLError) as error:
        raise ValueError("%s: cannot read: %s" % (path, error))
    if not isinstance(data, dict):
        raise ValueError("%s: not a mapping of %s" % (path, ", ".join(KEYS)))
    problems = ["%s: %s: missing" % (path, key) for key in KEYS if key not in data]
    problems += ["%s: %s: unknown key" % (path, key) for key in data
                 if key not in KEYS + OPTIONAL_KEYS]
    for key in ("x", "y", "z", "yaw") + OPTIONAL_KEYS:
        value = data.get(key)
        if key in data and (isinstance(value, bool) or not isinstance(value, (int, float))
                            or not math.isfinite(value)):
            problems.append("%s: %s: must be a finite number, got %r" % (path, key, value))
    for key in ("parent_frame", "child_frame"):
        if key in data and (not isinstance(data[key], str) or not data[key]):
            problems.append("%s: %s: must be a frame name, got %r" % (path, key, data[key]))
    if problems:
        raise ValueError("\n".join(problems))
    for key in OPTIONAL_KEYS:
        data.setdefault(key, 0.0)
    return data


def describe(urdf_path, mount):
    """The URDF text with laser_joint set to `mount`."""
    tree = ElementTree.parse(urdf_path)
    robot = tree.getroot()
    joint = robot.find("joint[@name='laser_joint']")
    if joint is None:
        raise ValueError("%s: no joint named laser_joint" % urdf_path)
    parent = joint.find("parent").get("link")
    if mount["parent_frame"] != parent:
        raise ValueError("calibration parent_frame '%s' is not the description's '%s'"
                         % (mount["parent_frame"], parent))
    child = joint.find("child")
    old_name = child.get("link")
    if mount["child_frame"] != old_name:
        for link in robot.findall("link[@name='%s']" % old_name):
            link.set("name", mount["child_frame"])
        child.set("link", mount["child_frame"])
    origin = joint.find("origin")
    origin.set("xyz", "%.6f %.6f %.6f" % (mount["x"], mount["y"], mount["z"]))
    origin.set("rpy", "%.9f %.9f %.9f" % (mount["roll"], mount["pitch"], mount["yaw"]))
    return ElementTree.tostring(robot, encoding="unicode")


def without_laser(urdf_path):
    """The URDF text without laser_joint and its child link."""
    tree = ElementTree.parse(urdf_path)
    robot = tree.getroot()
    joint = robot.find("joint[@name='laser_joint']")
    if joint is None:
        raise ValueError("%s: no joint named laser_joint" % urdf_path)
    child = joint.find("child").get("link")
    robot.remove(joint)
    for link in robot.findall("link[@name='%s']" % child):
        robot.remove(link)
    if robot.find("joint/parent[@link='%s']" % child) is not None:
        raise ValueError("%s: links hang below %s; cannot leave it out" % (urdf_path, child))
    return ElementTree.tostring(robot, encoding="unicode")


def main(argv):
    no_laser = len(argv) > 1 and argv[1] == "--no-laser"
    if no_laser:
        argv = argv[:1] + [None] + argv[2:]
    if len(argv) not in (2, 3) or argv[1] in ("-h", "--help"):
        sys.stderr.write(__doc__)
        return 1
    here = os.path.dirname(os.path.realpath(__file__))
    default_urdf = os.path.join(here, "..", "..", "config", "p3dx.urdf")
    if not os.path.exists(default_urdf):  # install space: share/ekf_slam/config
        import rospkg
        default_urdf = os.path.join(rospkg.RosPack().get_path("ekf_slam"), "config", "p3dx.urdf")
    urdf_path = argv[2] if len(argv) == 3 else default_urdf
    try:
        text = without_laser(urdf_path) if no_laser else describe(urdf_path, load_mount(argv[1]))
    except (ValueError, OSError, ElementTree.ParseError) as error:
        sys.stderr.write("p3dx_description: %s\n" % error)
        return 1
    sys.stdout.write('<?xml version="1.0"?>\n' + text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
