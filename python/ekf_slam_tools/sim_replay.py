"""A simulated run replayed offline (test/sim_replay.test,
test/sim_office_loop.test): the live SLAM node is paused after its loop, the
recorder's bag is cut to the scans the node used (its own map -> odom
dropped), ekf_slam_offline runs on it, and the live and offline answers and
their errors against the simulator's truth are compared."""
import bisect
import math
import os
import shutil
import subprocess
import time

import rosbag
import rospkg
import rospy
from ekf_slam.msg import LandmarkMap
from nav_msgs.msg import Path
from std_msgs.msg import Bool
from std_srvs.srv import Trigger

from ekf_slam_tools import se2

STAMP_TOLERANCE = 1e-6  # s: a scan is "the same" when its stamp matches to this
# m: "the smoother is not worse than the filter" is judged to this. On the
# carton loop both mean errors are ~2 mm, the precision to which a pose is
# matched to the truth at all (ekf_slam_tools.sim_monitor.TRUTH_SIGMA); one recording gave
# 1.7 mm smoothed against 1.5 mm filtered (with pipeline.min_landmark_range
# 1 m), a difference the comparison does not resolve.
SMOOTHED_TOLERANCE = 0.0005
# The relative part (smoothed_tolerance): one run's mean error is known to
# about 1/sqrt(30 independent poses) of itself.
SMOOTHED_RELATIVE_TOLERANCE = 1.0 / math.sqrt(30.0)


def smoothed_tolerance(filtered_error):
    """How much larger than the filter's the smoother's mean error may come
    out before "not worse" fails: SMOOTHED_TOLERANCE, plus
    SMOOTHED_RELATIVE_TOLERANCE of the filter's error. A run's poses are
    correlated over a few seconds (an office loop holds about 30 stretches
    whose errors vary apart), so one run's mean error is
    known to about 1/sqrt(30), 18 %, of itself, and the smoother, better in
    expectation, can come out behind in one noise draw by about that much:
    office loops gave 8.1 / 38.8 / 9.4 mm smoothed against 30.9 / 42.8 /
    46.6 mm filtered, and one 28.8 mm against 25.7 mm (+12 %). A smoother
    that fails outright is off by far more."""
    return SMOOTHED_TOLERANCE + SMOOTHED_RELATIVE_TOLERANCE * filtered_error


def read_trajectory(path):
    rows = []
    with open(path) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                rows.append(tuple(float(v) for v in line.split()[:4]))
    return rows


def position_errors(rows, truth):
    """Each pose's distance to the truth (interpolated at its stamp), with
    the map frame tied to the truth at the trajectory's first pose; poses
    outside the truth's time span are left out. Also the last pose's
    heading error (rad)."""
    rows = [r for r in rows if se2.interpolate(truth, r[0]) is not None]
    if not rows:
        return [], 0.0
    world_map = se2.compose(se2.interpolate(truth, rows[0][0]), se2.inverse(rows[0][1:4]))
    errors = []
    for r in rows:
        est = se2.compose(world_map, r[1:4])
        true = se2.interpolate(truth, r[0])
        errors.append(math.hypot(est[0] - true[0], est[1] - true[1]))
    return errors, se2.wrap(est[2] - true[2])


def mean_position_error(rows, truth):
    """Mean distance to the truth (position_errors) and the poses scored."""
    errors, _ = position_errors(rows, truth)
    return sum(errors) / len(errors), len(errors)


def pause_and_replay(test, directory, recorder, bag_path, wait_for_done=True):
    """Steps 1-3 of the module doc on the running system; `test` is the
    unittest.TestCase that asserts. Returns the figures."""
    if wait_for_done:
        finished = []
        rospy.Subscriber("waypoint_driver/done", Bool, lambda m: m.data and finished.append(1))
        deadline = time.time() + 200.0
        while not finished and time.time() < deadline and not rospy.is_shutdown():
            time.sleep(0.2)
        test.assertTrue(finished, "the waypoint driver did not finish the loop")
        rospy.sleep(1.0)
    rospy.wait_for_service("/ekf_slam/pause", 10.0)
    test.assertTrue(rospy.ServiceProxy("/ekf_slam/pause", Trigger)().success)
    rospy.sleep(1.0)  # a scan in flight finishes
    path = rospy.wait_for_message("path", Path, timeout=10.0)
    live_map = rospy.wait_for_message("landmark_map", LandmarkMap, timeout=10.0)
    live_stamps = [p.header.stamp.to_sec() for p in path.poses]
    last = path.poses[-1]
    live_last = (last.pose.position.x, last.pose.position.y, se2.yaw_of(last.pose.orientation))
    test.assertGreater(len(live_stamps), 100)
    test.assertGreater(len(live_map.landmarks), 5)

    # Stop the recorder (it closes the bag on shutdown).
    subprocess.run(["rosnode", "kill", recorder], check=True, stdout=subprocess.DEVNULL)
    os.makedirs(directory, exist_ok=True)
    deadline = time.time() + 30.0
    while (not os.path.exists(bag_path) or os.path.exists(bag_path + ".active")) and \
            time.time() < deadline:
        time.sleep(0.5)
    test.assertTrue(os.path.exists(bag_path), "the recorder left no closed bag")

    # The live node's scans, its inputs, and the truth.
    replay_path = os.path.join(directory, "replay.bag")
    wanted = sorted(live_stamps)
    kept_scans = 0
    truth = []
    with rosbag.Bag(bag_path) as source, rosbag.Bag(replay_path, "w") as target:
        for topic, msg, t in source.read_messages():
            if topic == "/scan":
                s = msg.header.stamp.to_sec()
                j = bisect.bisect_left(wanted, s)
                keep = any(abs(wanted[k] - s) < STAMP_TOLERANCE
                           for k in (j - 1, j) if 0 <= k < len(wanted))
                if not keep:
                    continue
                kept_scans += 1
            elif topic == "/tf":
                msg.transforms = [x for x in msg.transforms if x.child_frame_id != "odom"]
                if not msg.transforms:
                    continue
            elif topic == "/ground_truth/odom":
                p = msg.pose.pose
                truth.append((msg.header.stamp.to_sec(), p.position.x, p.position.y,
                              se2.yaw_of(p.orientation)))
            target.write(topic, msg, t)
    test.assertEqual(kept_scans, len(live_stamps), "the bag lacks scans the live node used")
    truth.sort()

    out = os.path.join(directory, "offline")
    shutil.rmtree(out, ignore_errors=True)
    config = os.path.join(rospkg.RosPack().get_path("ekf_slam"), "config", "ekf_slam_sim.yaml")
    run = subprocess.run(["roslaunch", "ekf_slam", "offline.launch", "bag:=" + replay_path,
                          "out:=" + out, "config:=" + config, "figures:=false"],
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         universal_newlines=True, timeout=300)
    print(run.stdout[-3000:])
    for name in ("trajectory_filtered.txt", "trajectory_smoothed.txt", "trajectory_rts.txt",
                 "landmarks.yaml", "map.pgm", "map.yaml", "report.txt"):
        test.assertTrue(os.path.exists(os.path.join(out, name)), name + " missing")

    filtered = read_trajectory(os.path.join(out, "trajectory_filtered.txt"))
    smoothed = read_trajectory(os.path.join(out, "trajectory_smoothed.txt"))  # full smoother
    rts = read_trajectory(os.path.join(out, "trajectory_rts.txt"))  # the thesis's RTS
    test.assertEqual(len(filtered), len(live_stamps))
    test.assertAlmostEqual(filtered[-1][0], live_stamps[-1], places=5)
    off = filtered[-1][1:4]
    with open(os.path.join(out, "landmarks.yaml")) as f:
        offline_landmarks = sum(1 for line in f if line.strip().startswith("- {id:"))
    filtered_error, n = mean_position_error(filtered, truth)
    smoothed_error, _ = mean_position_error(smoothed, truth)
    rts_error, _ = mean_position_error(rts, truth)
    r = {
        "scans": len(live_stamps),
        "live_landmarks": len(live_map.landmarks) + len(live_map.lines) + len(live_map.line_angles),
        "offline_landmarks": offline_landmarks,
        "distance": math.hypot(off[0] - live_last[0], off[1] - live_last[1]),
        "heading": abs(se2.wrap(off[2] - live_last[2])),
        "filtered_error": filtered_error,
        "smoothed_error": smoothed_error,
        "rts_error": rts_error,
    }
    print("live: %d scans, %d landmarks, last pose (%.4f, %.4f, %.5f)" % (
        r["scans"], r["live_landmarks"], *live_last))
    print("offline: %d landmarks, last pose (%.4f, %.4f, %.5f): %.4f m, %.5f rad apart" % (
        offline_landmarks, *off, r["distance"], r["heading"]))
    print("mean position error against the truth over %d scans: filtered %.4f m, "
          "RTS %.4f m, full smoother %.4f m" % (n, filtered_error, rts_error, smoothed_error))
    return r
