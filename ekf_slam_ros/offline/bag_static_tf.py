#!/usr/bin/python3
"""Republishes every static transform of a bag, latched, for a replay.

    rosrun ekf_slam bag_static_tf.py BAG [--resume SERVICE]

Reads each /tf_static message of BAG (tf2_msgs/TFMessage) and publishes all
their transforms at once on /tf_static with tf2_ros's static broadcaster,
then keeps them latched until it is stopped. A bag written without the
latching flag gives its robot's frames (base_link -> laser) only to the
subscribers present when `rosbag play` reaches that message; rviz, or any
node started later, would never get them. Where the bag holds the same child
frame more than once, the last one in the file wins, as it would for a tf2
listener.

--resume names the std_srvs/SetBool service of a `rosbag play --pause`
(`/bag_player/pause_playback`), called with false once the transforms are
latched: the scans then never come before the mount they need, however
long this node takes to start on a busy machine.

A bag that cannot be read is reported, naming it, and the player resumed
all the same; a bag without /tf_static is reported and nothing is published.
"""
import sys

import rosbag
import rospy
import tf2_ros
from std_srvs.srv import SetBool

from ekf_slam_tools.static_tf import static_transforms


def resume(service):
    rospy.wait_for_service(service)
    rospy.ServiceProxy(service, SetBool)(False)


def main():
    argv = rospy.myargv(sys.argv)
    resume_service = None
    if len(argv) == 4 and argv[2] == "--resume":
        resume_service = argv[3]
        argv = argv[:2]
    if len(argv) != 2 or argv[1] in ("-h", "--help"):
        sys.stderr.write(__doc__)
        return 1
    rospy.init_node("bag_static_tf")
    try:
        transforms = static_transforms(argv[1])
    except (OSError, rosbag.ROSBagException) as error:
        rospy.logerr("bag_static_tf: %s: %s", argv[1], error)
        if resume_service:
            resume(resume_service)
        return 1
    if not transforms:
        rospy.logwarn("bag_static_tf: %s holds no /tf_static: nothing to republish", argv[1])
    else:
        broadcaster = tf2_ros.StaticTransformBroadcaster()
        broadcaster.sendTransform(transforms)
        rospy.loginfo("bag_static_tf: %d static transform(s) of %s latched on /tf_static: %s",
                      len(transforms), argv[1],
                      ", ".join("%s -> %s" % (t.header.frame_id, t.child_frame_id)
                                for t in transforms))
    if resume_service:
        resume(resume_service)
    rospy.spin()
    return 0


if __name__ == "__main__":
    sys.exit(main())
