"""The static transforms of a bag (its robot's frames, base_link -> laser),
for a replay that must hand them to every listener however late it
subscribes: a bag written without the latching flag gives them only to the
subscribers present when `rosbag play` reaches that message."""
import rosbag


def static_transforms(path):
    """Every transform on /tf_static of the bag at `path`, one per child frame
    (the last written, as a tf2 listener would keep it), in the order the
    child frames first appear."""
    by_child = {}
    with rosbag.Bag(path) as bag:
        for _topic, message, _stamp in bag.read_messages(topics=["/tf_static"]):
            for transform in message.transforms:
                by_child[transform.child_frame_id] = transform
    return list(by_child.values())
