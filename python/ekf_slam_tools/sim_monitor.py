"""Watches a simulated SLAM run (sim.launch) and scores it against the
simulator's ground truth: used by `make demo` (writes output/) and by the
office-loop rostest (test/sim_office_loop.test asserts on the same numbers).

It records the SLAM pose (`pose`, map frame, with covariance), the robot's
own odometry (`odom`) and the truth (`ground_truth/odom`, world frame) until
the waypoint driver reports `done` (or until the true robot has not moved for
--stall-timeout seconds, a lost run: scored as it stands, named in the
report), then asks the SLAM node to smooth and to save its landmark map, and
writes into OUT:
  trajectory_slam.txt, trajectory_odometry.txt, trajectory_true.txt
      `stamp x y theta`, all in the SLAM map frame
  landmarks.yaml   the SLAM node's own save_map file
  report.txt       final and mean pose errors, average NEES with its band,
                   landmarks, duplicates
  demo.png         the world, the landmarks with 95 % ellipses and the three
                   paths

Frames. The SLAM map frame is the robot's pose at the first SLAM iteration;
the truth is in the world. The two are tied at the first SLAM pose:
T_world_map = truth(t0) * slam(t0)^-1, and likewise for odometry, so every
error below is what the estimate accumulated after t0.

usage (as a ROS node): sim_monitor.py --out DIR [--world office] [--timeout S]
"""
import argparse
import math
import os
import sys
import threading
import time

import numpy as np
import rospkg

from ekf_slam_tools.se2 import compose, interpolate, inverse, transform_point, wrap
from ekf_slam_tools.stats import nees_band, nees_effective_samples, whitened
from ekf_slam_tools.worlds import read_world_image, world_vertices


# --- scoring ------------------------------------------------------------------
# Uncertainty of the comparison itself, added to the filter's covariance for
# the NEES: the truth is integrated in 10 ms simulator steps and published at
# 50 Hz, and a pose is matched to it by stamps taken in two processes (the
# scan's first-beam stamp is estimated by the LMS200 driver), a few ms apart:
# ~2 mm at 0.4 m/s and ~1 mrad at 0.3 rad/s. Without it the first metres,
# where the filter's σ is a fraction of a millimetre, dominate the average.
TRUTH_SIGMA = (0.002, 0.002, 0.001)  # m, m, rad


def score(truth, slam, odom, landmarks, vertices, run_samples=None):
    """truth/odom: [(t, x, y, th)] (world / odom frame); slam: [(t, x, y, th,
    cov3x3)] (map frame); landmarks: [(id, x, y, cov2x2)] (map frame);
    vertices: [(x, y)] world. run_samples: the independent samples one run
    of this loop is worth, measured over many runs (the NEES band's count);
    None: estimated from this run's errors alone, which counts too many
    when part of the error lasts the whole run. Returns a dict of results
    plus the aligned tracks."""
    # Poses the truth and the odometry both cover (the monitor may have
    # subscribed a moment after the first SLAM pose was published).
    usable = [s for s in slam
              if interpolate(truth, s[0]) is not None and interpolate(odom, s[0]) is not None]
    if len(usable) < 2:
        raise RuntimeError("fewer than 2 SLAM poses overlap the ground truth and the odometry "
                           "in time (%d SLAM poses, %d truth, %d odometry samples)" %
                           (len(slam), len(truth), len(odom)))
    t0 = usable[0][0]
    world_map = compose(interpolate(truth, t0), inverse(usable[0][1:4]))
    map_world = inverse(world_map)
    odom0 = interpolate(odom, t0)
    if odom0 is None:
        raise RuntimeError("no odometry at the first SLAM pose")
    map_odom = compose(usable[0][1:4], inverse(odom0))

    rows = []
    nees = []
    white = []
    for s in usable:
        t = s[0]
        true_map = compose(map_world, interpolate(truth, t))
        est = s[1:4]
        e = np.array([est[0] - true_map[0], est[1] - true_map[1], wrap(est[2] - true_map[2])])
        cov = np.asarray(s[4]) + np.diag(np.square(TRUTH_SIGMA))
        try:
            white.append(whitened(e, cov))
            nees.append(float(white[-1] @ white[-1]))
        except np.linalg.LinAlgError:
            pass
        o = interpolate(odom, t)
        odom_map = compose(map_odom, o) if o is not None else None
        rows.append((t, est, true_map, odom_map, e, np.sqrt(np.maximum(np.diag(cov), 0.0)),
                     nees[-1] if nees else float("nan")))

    last = rows[-1]
    final_pos = math.hypot(last[4][0], last[4][1])
    final_head = abs(math.degrees(last[4][2]))
    mean_pos = float(np.mean([math.hypot(r[4][0], r[4][1]) for r in rows]))
    odom_rows = [r for r in rows if r[3] is not None]
    lo = odom_rows[-1]
    odom_final_pos = math.hypot(lo[3][0] - lo[2][0], lo[3][1] - lo[2][1])
    odom_final_head = abs(math.degrees(wrap(lo[3][2] - lo[2][2])))
    odom_errors = [math.hypot(r[3][0] - r[2][0], r[3][1] - r[2][1]) for r in odom_rows]
    odom_mean_pos = float(np.mean(odom_errors))
    odom_max_pos = float(np.max(odom_errors))
    max_pos = float(np.max([math.hypot(r[4][0], r[4][1]) for r in rows]))
    n_eff = nees_effective_samples(white)
    n_band = run_samples if run_samples else n_eff
    band = nees_band(3, n_band) if n_band >= 1 else (float("nan"), float("nan"))

    # Duplicates: two landmarks statistically at the same place (3 sigma on
    # their difference) next to the same true corner.
    verts_map = [transform_point(map_world, v) for v in vertices]
    nearest = {}
    for lm in landmarks:
        best, best_d = None, 0.3
        for k, v in enumerate(verts_map):
            d = math.hypot(lm[1] - v[0], lm[2] - v[1])
            if d < best_d:
                best, best_d = k, d
        if best is not None:
            nearest.setdefault(best, []).append(lm)
    duplicates = []
    for group in nearest.values():
        for i in range(len(group)):
            for j in range(i + 1, len(group)):
                a, b = group[i], group[j]
                d = np.array([a[1] - b[1], a[2] - b[2]])
                c = np.asarray(a[3]) + np.asarray(b[3])
                if float(d @ np.linalg.solve(c, d)) < 11.83:
                    duplicates.append((a[0], b[0]))
    return {
        "poses": len(rows),
        "duration": rows[-1][0] - rows[0][0],
        "final_position_error": final_pos,
        "final_heading_error_deg": final_head,
        "mean_position_error": mean_pos,
        "odometry_final_position_error": odom_final_pos,
        "odometry_final_heading_error_deg": odom_final_head,
        "odometry_mean_position_error": odom_mean_pos,
        "odometry_max_position_error": odom_max_pos,
        "max_position_error": max_pos,
        "nees_average": float(np.mean(nees)) if nees else float("nan"),
        "nees_samples": len(nees),
        "nees_effective_samples": n_eff,
        "nees_run_samples": run_samples,
        "nees_band_95": band,
        "landmarks": len(landmarks),
        "landmarks_near_true_corners": sum(len(g) for g in nearest.values()),
        "duplicates": duplicates,
        "rows": rows,
        "map_world": map_world,
    }


def report_text(r):
    return "\n".join([
        "SLAM poses scored: %d over %.1f s" % (r["poses"], r["duration"]),
        "final pose error: %.3f m, %.2f deg (odometry alone: %.3f m, %.2f deg)" % (
            r["final_position_error"], r["final_heading_error_deg"],
            r["odometry_final_position_error"], r["odometry_final_heading_error_deg"]),
        "mean position error: %.3f m, largest %.3f m (odometry alone: %.3f m, largest %.3f m)" % (
            r["mean_position_error"], r["max_position_error"], r["odometry_mean_position_error"],
            r["odometry_max_position_error"]),
        "average pose NEES: %.2f over %d poses (%s), 95%% band %.2f..%.2f "
        "(truth matched to %.0f mm, %.0f mrad)" % (
            r["nees_average"], r["nees_samples"], nees_samples_text(r),
            r["nees_band_95"][0], r["nees_band_95"][1], 1e3 * TRUTH_SIGMA[0], 1e3 * TRUTH_SIGMA[2]),
        "landmarks: %d (%d within 0.3 m of a true corner), duplicated: %d" % (
            r["landmarks"], r["landmarks_near_true_corners"], len(r["duplicates"])),
    ] + live_map_lines(r.get("live_map")) +
        (["ended early: " + r["ended_early"]] if r.get("ended_early") else [])) + "\n"


def nees_samples_text(r):
    if r.get("nees_run_samples"):
        return ("a loop worth %.1f independent samples over many runs; %.0f by this run's "
                "errors alone" % (r["nees_run_samples"], r["nees_effective_samples"]))
    return "%.0f independent" % r["nees_effective_samples"]


def live_map_lines(live):
    if not live:
        return []
    delay = live["map_delay"]
    return ["live map: %d grids while driving, the first %s after the robot moved; known cells "
            "%d -> %d; map_metadata %s the last grid's info" % (
                live["maps"], "%.1f s" % delay if delay is not None else "never",
                live["first_known_cells"], live["last_known_cells"],
                "matches" if live["metadata_matches"] else "DIFFERS from")]


def write_outputs(out, r, landmarks, world_yaml):
    os.makedirs(out, exist_ok=True)
    names = {"slam": 1, "true": 2, "odometry": 3}
    for name, k in names.items():
        with open(os.path.join(out, "trajectory_%s.txt" % name), "w") as f:
            f.write("# stamp x y theta  (SLAM map frame)\n")
            for row in r["rows"]:
                p = row[k]
                if p is not None:
                    f.write("%.6f %.4f %.4f %.5f\n" % (row[0], p[0], p[1], p[2]))
    with open(os.path.join(out, "errors.txt"), "w") as f:
        f.write("# stamp  error x y theta (SLAM - truth, map frame; m, m, rad)  "
                "sigma x y theta (the filter's)  NEES\n")
        for row in r["rows"]:
            e, sd = row[4], row[5]
            f.write("%.6f %.4f %.4f %.5f %.4f %.4f %.5f %.2f\n" % (
                row[0], e[0], e[1], e[2], sd[0], sd[1], sd[2], row[6]))
    with open(os.path.join(out, "report.txt"), "w") as f:
        f.write(report_text(r))
    plot(os.path.join(out, "demo.png"), r, landmarks, world_yaml)


def plot(path, r, landmarks, world_yaml):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(10, 6.5))
    if world_yaml and os.path.exists(world_yaml):
        xs, ys = read_world_image(world_yaml)
        m = r["map_world"]
        c, s = math.cos(m[2]), math.sin(m[2])
        ax.scatter(m[0] + c * xs - s * ys, m[1] + s * xs + c * ys, s=1.0, c="0.7",
                   marker="s", linewidths=0, label="world (truth)", rasterized=True)
    for k, label, style in [(2, "ground truth", "k-"), (3, "odometry", "r--"), (1, "SLAM", "b-")]:
        pts = [row[k] for row in r["rows"] if row[k] is not None]
        ax.plot([p[0] for p in pts], [p[1] for p in pts], style, lw=1.2, label=label)
    t = np.linspace(0.0, 2.0 * math.pi, 40)
    for i, lm in enumerate(landmarks):
        w, v = np.linalg.eigh(np.asarray(lm[3]))
        axes = np.sqrt(np.maximum(w, 0.0) * 5.991)  # 95 %, 2 dof
        e = v @ np.vstack([axes[0] * np.cos(t), axes[1] * np.sin(t)])
        ax.plot(lm[1] + e[0], lm[2] + e[1], "g-", lw=0.8,
                label="landmarks, 95 % ellipses" if i == 0 else None)
        ax.plot(lm[1], lm[2], "g+", ms=4)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m] (map frame)")
    ax.set_ylabel("y [m]")
    ax.set_title("final error %.3f m / %.2f deg (odometry %.2f m), NEES %.2f" % (
        r["final_position_error"], r["final_heading_error_deg"],
        r["odometry_final_position_error"], r["nees_average"]))
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# --- the ROS side ----------------------------------------------------------------
class Recorder:
    def __init__(self, slam_node):
        import rospy
        from geometry_msgs.msg import PoseWithCovarianceStamped
        from nav_msgs.msg import MapMetaData, OccupancyGrid, Odometry
        from std_msgs.msg import Bool
        self.truth, self.slam, self.odom = [], [], []
        self.done = False
        self.slam_node = slam_node
        # The live grid: when the true robot first moved (wall time), each
        # `map` as it arrived while the robot drove (wall time, its info,
        # its known cells) and the newest `map_metadata`.
        self.moved_at = None
        self.maps = []
        self.metadata = None
        self._lock = threading.Lock()
        rospy.Subscriber("map", OccupancyGrid, self._map, queue_size=2)
        rospy.Subscriber("map_metadata", MapMetaData, self._metadata, queue_size=2)
        rospy.Subscriber("ground_truth/odom", Odometry, self._truth, queue_size=200)
        rospy.Subscriber("odom", Odometry, self._odom, queue_size=200)
        rospy.Subscriber("pose", PoseWithCovarianceStamped, self._slam, queue_size=200)
        rospy.Subscriber("waypoint_driver/done", Bool, self._done, queue_size=2)

    @staticmethod
    def _yaw(q):
        return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))

    def _append(self, track, stamp, pose, extra=None):
        t = stamp.to_sec()
        if track and t <= track[-1][0]:
            return  # keep the track time-sorted
        row = (t, pose.position.x, pose.position.y, self._yaw(pose.orientation))
        track.append(row + ((extra,) if extra is not None else ()))

    def _truth(self, msg):
        self._append(self.truth, msg.header.stamp, msg.pose.pose)
        if self.moved_at is None and len(self.truth) > 1:
            first, last = self.truth[0], self.truth[-1]
            if math.hypot(last[1] - first[1], last[2] - first[2]) > 0.05:
                self.moved_at = time.time()

    def _map(self, msg):
        if self.done:
            return  # what the end's ~smooth publishes is not the live map
        known = sum(1 for v in msg.data if v >= 0)
        with self._lock:
            self.maps.append((time.time(), msg.info, known))

    def _metadata(self, msg):
        with self._lock:
            self.metadata = msg

    def live_map(self):
        """The live grid as the run saw it: the seconds from the robot's
        first motion to the first `map` after it (None when none came), the
        number of maps while it drove, the known cells of the first and the
        last, and whether the newest `map_metadata` equals the newest map's
        info."""
        with self._lock:
            maps, metadata = list(self.maps), self.metadata
        moved = self.moved_at
        after = [m for m in maps if moved is not None and m[0] >= moved]
        same = bool(maps) and metadata is not None and metadata_equal(maps[-1][1], metadata)
        return {
            "map_delay": after[0][0] - moved if after else None,
            "maps": len(maps),
            "first_known_cells": maps[0][2] if maps else 0,
            "last_known_cells": maps[-1][2] if maps else 0,
            "metadata_matches": same,
        }

    def _odom(self, msg):
        self._append(self.odom, msg.header.stamp, msg.pose.pose)

    def _slam(self, msg):
        c = msg.pose.covariance
        cov = [[c[0], c[1], c[5]], [c[6], c[7], c[11]], [c[30], c[31], c[35]]]
        self._append(self.slam, msg.header.stamp, msg.pose.pose, cov)

    def _done(self, msg):
        self.done = self.done or msg.data

    def stalled(self, window, distance=0.05, angle=0.1):
        """A description when the true robot has stayed within `distance`
        and `angle` for the last `window` seconds of data after SLAM began
        (against a wall it was steered into, or stopped for a lost pose),
        else None."""
        truth = list(self.truth)
        if not self.slam or len(truth) < 2 or truth[-1][0] - window < self.slam[0][0]:
            return None
        last = truth[-1]
        for row in reversed(truth):
            if (math.hypot(row[1] - last[1], row[2] - last[2]) > distance or
                    abs(wrap(row[3] - last[3])) > angle):
                return None
            if last[0] - row[0] >= window:
                return ("the robot has not moved for %.0f s, at (%.2f, %.2f) in the world (steered "
                        "into a wall, or waiting for a lost pose): a lost run, scored as it stands"
                        % (window, last[1], last[2]))
        return None

    def finish(self, out):
        """Smooth, save the landmark map into `out`, return the landmarks."""
        import rospy
        import yaml
        from std_srvs.srv import Trigger
        from ekf_slam.srv import SaveMap
        os.makedirs(out, exist_ok=True)
        try:
            rospy.wait_for_service(self.slam_node + "/smooth", 10.0)
            rospy.ServiceProxy(self.slam_node + "/smooth", Trigger)()
        except Exception as e:  # the score does not depend on it
            rospy.logwarn("sim_monitor: smooth failed: %s", e)
        path = os.path.join(os.path.abspath(out), "landmarks.yaml")
        rospy.wait_for_service(self.slam_node + "/save_map", 10.0)
        answer = rospy.ServiceProxy(self.slam_node + "/save_map", SaveMap)(path)
        if not answer.success:
            raise RuntimeError("save_map failed: " + answer.message)
        with open(path) as f:
            data = yaml.safe_load(f)
        landmarks = []
        for lm in data.get("landmarks", []) or []:
            c = lm["covariance"]
            cov = [[c[0], c[1]], [c[2], c[3]]] if len(c) == 4 else [[c[0], c[1]], [c[1], c[2]]]
            landmarks.append((lm["id"], lm["x"], lm["y"], cov))
        return landmarks


def metadata_equal(a, b):
    """Two nav_msgs/MapMetaData describe the same grid (load time aside)."""
    return (a.resolution == b.resolution and a.width == b.width and a.height == b.height and
            a.origin == b.origin)


def resume_when_recording(recorder_node, slam_node="/ekf_slam", topic="/scan", timeout=60.0):
    """For a SLAM node started paused (start_paused): waits until
    `recorder_node` subscribes to `topic` (and a second more for the
    connection), then calls the node's ~resume, so that the recording holds
    every scan the map is built from."""
    import rosgraph
    import rospy
    from std_srvs.srv import Trigger
    master = rosgraph.Master(rospy.get_name())
    deadline = time.time() + timeout
    while time.time() < deadline and not rospy.is_shutdown():
        _, subscribers, _ = master.getSystemState()
        if any(t == topic and recorder_node in nodes for t, nodes in subscribers):
            break
        time.sleep(0.1)
    else:
        raise RuntimeError("%s did not subscribe to %s within %.0f s" %
                           (recorder_node, topic, timeout))
    time.sleep(1.0)
    rospy.wait_for_service(slam_node + "/resume", timeout)
    if not rospy.ServiceProxy(slam_node + "/resume", Trigger)().success:
        raise RuntimeError(slam_node + "/resume refused")


def run(args):
    import rospy
    rospy.init_node("sim_monitor")
    recorder = Recorder(args.slam_node)  # listening before SLAM may start
    if getattr(args, "resume_after_recorder", None):
        resume_when_recording(args.resume_after_recorder, args.slam_node)
    start = time.time()
    rate = rospy.Rate(5)
    stall_window = getattr(args, "stall_timeout", 30.0)
    ended_early = None
    while not rospy.is_shutdown() and not recorder.done:
        if time.time() - start > args.timeout:
            raise RuntimeError("the waypoint driver did not finish within %.0f s" % args.timeout)
        ended_early = recorder.stalled(stall_window)
        if ended_early:
            rospy.logwarn("sim_monitor: " + ended_early)
            break
        rate.sleep()
    rospy.sleep(1.0)  # the last scan's pose
    live_map = recorder.live_map()
    recorder.done = True
    landmarks = recorder.finish(args.out)
    result = score(recorder.truth, recorder.slam, recorder.odom, landmarks,
                   world_vertices(args.world), getattr(args, "run_samples", None))
    result["ended_early"] = ended_early
    result["live_map"] = live_map
    world_yaml = os.path.join(rospkg.RosPack().get_path("ekf_slam"), "config", "worlds",
                              args.world + ".yaml")
    write_outputs(args.out, result, landmarks, world_yaml)
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--world", default="office")
    parser.add_argument("--timeout", type=float, default=600.0)
    parser.add_argument("--stall-timeout", type=float, default=30.0,
                        help="s without the true robot moving that end a run as lost")
    parser.add_argument("--slam-node", default="/ekf_slam")
    parser.add_argument("--run-samples", type=float, metavar="N",
                        help="independent samples one run of this loop is worth, from the spread "
                        "of many runs (tools/dev/office_monte_carlo.sh), for the NEES band; "
                        "default: estimated from this run alone")
    parser.add_argument("--resume-after-recorder", metavar="NODE",
                        help="SLAM was started paused: resume it once NODE records /scan")
    args, _ = parser.parse_known_args([a for a in sys.argv[1:] if not a.startswith("__")])
    result = run(args)
    sys.stdout.write(report_text(result))

