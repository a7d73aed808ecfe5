#!/usr/bin/python3
"""rostest checks of lms200_node against lms200_emulator on a pseudo-terminal.

The emulator publishes its ground truth (~true_scan: noise-free ranges with
the true first-beam stamp; ~corrupted_scan: scans sent with an injected
fault; ~events). Which checks run is chosen by the private parameter
`checks` (comma-separated): init, ranges, stamps, faults, reconnect.
"""
import math
import threading
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from sensor_msgs.msg import LaserScan
from std_msgs.msg import String


class Lms200Observer:
    def __init__(self):
        self.lock = threading.Lock()
        self.scans = []        # (receipt wall time, LaserScan)
        self.truths = []       # LaserScan with true stamps and noise-free ranges
        self.corrupted = []
        self.events = []       # (receipt wall time, text)
        self.diagnostics = {}  # latest key/value of the LMS200 status
        rospy.Subscriber("scan", LaserScan, self._on_scan, queue_size=50)
        rospy.Subscriber("lms200_emulator/true_scan", LaserScan, self._on_truth, queue_size=50)
        rospy.Subscriber("lms200_emulator/corrupted_scan", LaserScan, self._on_corrupted,
                         queue_size=50)
        rospy.Subscriber("lms200_emulator/events", String, self._on_event, queue_size=50)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self._on_diagnostics, queue_size=50)

    def _on_scan(self, msg):
        with self.lock:
            self.scans.append((time.time(), msg))

    def _on_truth(self, msg):
        with self.lock:
            self.truths.append(msg)

    def _on_corrupted(self, msg):
        with self.lock:
            self.corrupted.append(msg)

    def _on_event(self, msg):
        with self.lock:
            self.events.append((time.time(), msg.data))

    def _on_diagnostics(self, msg):
        for status in msg.status:
            if status.name.endswith("LMS200"):
                with self.lock:
                    self.diagnostics = {kv.key: kv.value for kv in status.values}
                    self.diagnostics["_message"] = status.message

    def wait_for(self, condition, timeout, what):
        deadline = time.time() + timeout
        while time.time() < deadline and not rospy.is_shutdown():
            with self.lock:
                if condition():
                    return
            time.sleep(0.05)
        with self.lock:
            raise AssertionError("timed out after %.0f s waiting for %s (diagnostics: %s)"
                                 % (timeout, what, self.diagnostics))

    def matched(self):
        """Pairs (published scan, truth) whose stamps are within 20 ms."""
        with self.lock:
            truths = list(self.truths)
            scans = list(self.scans)
        pairs = []
        for _, scan in scans:
            stamp = scan.header.stamp.to_sec()
            best = min(truths, key=lambda t: abs(t.header.stamp.to_sec() - stamp), default=None)
            if best is not None and abs(best.header.stamp.to_sec() - stamp) < 0.02:
                pairs.append((scan, best))
        return pairs


class Lms200NodeTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("lms200_rostest")
        cls.obs = Lms200Observer()
        cls.checks = set(rospy.get_param("~checks", "init,ranges,stamps").split(","))
        cls.noise = rospy.get_param("~noise", 0.01)
        cls.scans_wanted = rospy.get_param("~scans", 30)

    def setUp(self):
        # Every check needs the node streaming first (initialisation at 9600
        # baud can take a few seconds).
        self.obs.wait_for(lambda: len(self.obs.scans) >= 3, 45.0, "the first scans")

    def test_init_switches_to_configured_baud(self):
        if "init" not in self.checks:
            return
        self.obs.wait_for(lambda: self.obs.diagnostics.get("Baud") == "38400", 20.0,
                          "diagnostics reporting 38400 baud")
        # 181 values at 38400 baud: 372 bytes take 97 ms, so a scan every 8
        # mirror turns (9.375 Hz); at 9600 baud it would be about 2.4 Hz.
        self.obs.wait_for(lambda: float(self.obs.diagnostics.get("Scan rate (Hz)", "0")) > 8.0,
                          20.0, "diagnostics reporting a scan rate above 8 Hz")
        self.assertAlmostEqual(float(self.obs.diagnostics["Expected scan rate (Hz)"]), 9.38,
                               places=2)
        with self.obs.lock:
            events = [text for _, text in self.obs.events]
        self.assertIn("baud 38400", events, "the emulator never switched to 38400: %s" % events)
        _, scan = self.obs.scans[-1]
        self.assertEqual(len(scan.ranges), 181)
        self.assertAlmostEqual(scan.angle_min, -math.pi / 2, places=5)
        self.assertAlmostEqual(scan.angle_max, math.pi / 2, places=5)
        self.assertAlmostEqual(scan.angle_increment, math.radians(1.0), places=6)
        self.assertAlmostEqual(scan.time_increment, (1 / 75.0) / 360.0, places=8)
        self.assertAlmostEqual(scan.range_max, 8.182, places=3)
        self.assertEqual(scan.header.frame_id, "laser")

    def test_ranges_match_truth_within_noise(self):
        if "ranges" not in self.checks:
            return
        self.obs.wait_for(lambda: len(self.obs.scans) >= self.scans_wanted, 60.0,
                          "%d scans" % self.scans_wanted)
        pairs = self.obs.matched()
        self.assertGreaterEqual(len(pairs), self.scans_wanted - 2)
        tolerance = 5 * self.noise + 0.0015  # 5 sigma + quantisation
        finite = 0
        for scan, truth in pairs:
            self.assertEqual(len(scan.ranges), len(truth.ranges))
            for i, (r, t) in enumerate(zip(scan.ranges, truth.ranges)):
                if math.isinf(t) or t > scan.range_max:
                    self.assertTrue(math.isinf(r) or r > scan.range_max - tolerance,
                                    "beam %d: truth %.3f (no return), published %.3f" % (i, t, r))
                else:
                    self.assertFalse(math.isnan(r), "beam %d is NaN" % i)
                    self.assertLess(abs(r - t), tolerance,
                                    "beam %d: truth %.3f published %.3f" % (i, t, r))
                    finite += 1
        self.assertGreater(finite, len(pairs) * 100, "too few beams hit the room")
        rospy.loginfo("ranges: %d scans, %d finite beams within %.3f m", len(pairs), finite,
                      tolerance)

    def test_stamp_is_first_beam_time(self):
        if "stamps" not in self.checks:
            return
        self.obs.wait_for(lambda: len(self.obs.scans) >= self.scans_wanted, 60.0,
                          "%d scans" % self.scans_wanted)
        signed = [s.header.stamp.to_sec() - t.header.stamp.to_sec() for s, t in self.obs.matched()]
        print("STAMP_ERRORS_MS " + " ".join("%.2f" % (e * 1e3) for e in signed))
        errors = sorted(abs(e) for e in signed)
        self.assertGreaterEqual(len(errors), self.scans_wanted - 2)
        median = errors[len(errors) // 2]
        p95 = errors[int(len(errors) * 0.95)]
        rospy.loginfo("stamp error over %d scans: median %.3f ms, p95 %.3f ms, max %.3f ms",
                      len(errors), median * 1e3, p95 * 1e3, errors[-1] * 1e3)
        print("STAMP_ERROR_MS median=%.3f p95=%.3f max=%.3f n=%d"
              % (median * 1e3, p95 * 1e3, errors[-1] * 1e3, len(errors)))
        # The median is the driver's accuracy (0.1-0.3 ms on an idle host).
        # The tail also carries the host's scheduling, which a shared
        # machine can stretch past 2 ms for seconds at a time; what must
        # never happen there is a scan given to the wrong mirror turn, so
        # the tail is held to half a mirror period (6.7 ms).
        self.assertLess(median, 0.002)
        self.assertLess(p95, 0.5 / 75.0)

    def test_corrupted_scans_are_counted_and_never_published(self):
        if "faults" not in self.checks:
            return
        self.obs.wait_for(lambda: len(self.obs.corrupted) >= 5, 60.0, "5 corrupted scans")
        with self.obs.lock:
            corrupted = [c.header.stamp.to_sec() for c in self.obs.corrupted]
        # A lost byte usually breaks the checksum, but one lost in the header
        # makes an impossible frame instead: count both.
        def rejected():
            d = self.obs.diagnostics
            return sum(int(d.get(key, "0")) for key in ("CRC errors", "Bad frames",
                                                        "Malformed scans"))
        self.obs.wait_for(lambda: rejected() >= len(corrupted), 15.0,
                          "diagnostics counting at least %d rejected telegrams" % len(corrupted))
        with self.obs.lock:
            published = [s.header.stamp.to_sec() for _, s in self.obs.scans]
            truths = len(self.obs.truths)
        print("FAULTS corrupted=%d clean_truths=%d published=%d crc_errors=%s"
              % (len(corrupted), truths, len(published), self.obs.diagnostics.get("CRC errors")))
        for stamp in corrupted:
            nearest = min(abs(p - stamp) for p in published)
            self.assertGreater(nearest, 0.02, "a corrupted scan was published")
        # The clean scans still come through (a few may be lost to resync).
        self.assertGreaterEqual(len(self.obs.matched()), 0.8 * truths)

    def test_recovers_from_unplug_within_5s(self):
        if "reconnect" not in self.checks:
            return
        self.obs.wait_for(lambda: any(e == "replugged" for _, e in self.obs.events), 60.0,
                          "the emulator's replug")
        with self.obs.lock:
            replug_time = [t for t, e in self.obs.events if e == "replugged"][0]
        self.obs.wait_for(lambda: any(t > replug_time + 0.05 for t, _ in self.obs.scans), 10.0,
                          "a scan after the replug")
        with self.obs.lock:
            first = min(t for t, _ in self.obs.scans if t > replug_time + 0.05)
        recovery = first - replug_time
        print("RECOVERY_S %.3f" % recovery)
        rospy.loginfo("first scan %.2f s after the replug", recovery)
        self.assertLess(recovery, 5.0)
        self.obs.wait_for(lambda: int(self.obs.diagnostics.get("Link losses", "0")) >= 1 and
                          int(self.obs.diagnostics.get("Initialisations", "0")) >= 2, 10.0,
                          "diagnostics reporting the link loss and re-initialisation")


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "lms200_rostest", Lms200NodeTest)
