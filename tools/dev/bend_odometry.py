#!/usr/bin/python3
"""Writes a copy of a bag whose wheel odometry is bent by a constant heading bias.

Every odometry increment (between consecutive /odom messages) gets an extra
turn of `bias` degrees per metre driven, and the odometry is integrated
again from the first pose. /odom and the odom -> base_link transforms on /tf
carry the bent poses; every other message is copied unchanged. Used to make
a log whose loops come back far from where the drifted estimate expects
them, for testing loop closure that must not depend on small drift.

usage: bend_odometry.py INPUT.bag OUTPUT.bag --degrees-per-metre 1.0
"""
import argparse
import math
import sys

import rosbag

from ekf_slam_tools.se2 import yaw_of


def set_yaw(q, yaw):
    q.x, q.y, q.z, q.w = 0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)


class Bender:
    """Maps raw odometry poses, in stamp order of arrival, to bent ones."""

    def __init__(self, bias_per_metre):
        self.bias = bias_per_metre
        self.last_raw = None
        self.bent = None
        self.cache = {}

    def bend(self, key, x, y, yaw):
        if key in self.cache:
            return self.cache[key]
        if self.last_raw is None:
            self.bent = (x, y, yaw)
        else:
            lx, ly, lyaw = self.last_raw
            c, s = math.cos(lyaw), math.sin(lyaw)
            dx, dy = x - lx, y - ly
            fx, fy = c * dx + s * dy, -s * dx + c * dy  # increment in the last frame
            dyaw = yaw - lyaw
            bx, by, byaw = self.bent
            c, s = math.cos(byaw), math.sin(byaw)
            byaw_new = byaw + dyaw + self.bias * math.hypot(fx, fy)
            self.bent = (bx + c * fx - s * fy, by + s * fx + c * fy, byaw_new)
        self.last_raw = (x, y, yaw)
        self.cache[key] = self.bent
        return self.bent


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("input")
    parser.add_argument("output")
    parser.add_argument("--degrees-per-metre", type=float, required=True)
    args = parser.parse_args()
    bender = Bender(math.radians(args.degrees_per_metre))
    bent_messages = 0
    with rosbag.Bag(args.input) as source, rosbag.Bag(args.output, "w") as sink:
        for topic, msg, t in source.read_messages():
            if topic == "/odom" or msg._type == "nav_msgs/Odometry":
                p = msg.pose.pose
                key = (msg.header.stamp.secs, msg.header.stamp.nsecs)
                x, y, yaw = bender.bend(key, p.position.x, p.position.y, yaw_of(p.orientation))
                p.position.x, p.position.y = x, y
                set_yaw(p.orientation, yaw)
                bent_messages += 1
            elif msg._type == "tf2_msgs/TFMessage" and topic == "/tf":
                for tf in msg.transforms:
                    if tf.child_frame_id.lstrip("/") != "base_link":
                        continue
                    tr = tf.transform
                    key = (tf.header.stamp.secs, tf.header.stamp.nsecs)
                    x, y, yaw = bender.bend(key, tr.translation.x, tr.translation.y,
                                            yaw_of(tr.rotation))
                    tr.translation.x, tr.translation.y = x, y
                    set_yaw(tr.rotation, yaw)
                    bent_messages += 1
            sink.write(topic, msg, t)
    if bent_messages == 0:
        sys.exit("bend_odometry: no /odom or odom -> base_link message in " + args.input)
    print("bend_odometry: %d odometry poses bent by %.3f deg/m" % (bent_messages,
                                                                 args.degrees_per_metre))


if __name__ == "__main__":
    main()
