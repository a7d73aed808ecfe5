#!/usr/bin/python3
"""Starts rviz with a config on a private Xvfb display, lets it render for a
while, writes a PNG screenshot of the screen and reports every error rviz
printed. Used by the rviz smoke rostest (test/rviz_smoke.test) and to make
the README's screenshot:

  rviz_screenshot.py --config config/rviz/sim.rviz --out shot.png [--wait 20]
                     [--at-clock T [--pause-service /bag_player/pause_playback]]

--at-clock T keeps rviz running until /clock reaches T (a replay's log
time, s), pauses the bag player through --pause-service if given, renders
--wait s more, takes the shot and resumes the player: a view of a replay at
a chosen moment (tools/dev/replay_screenshots.sh).

Needs a ROS master (rviz is a ROS node), Xvfb, xwd, rviz. Exit status 0 when
rviz ran for the whole wait, the screenshot was written and rviz printed no
error; otherwise 1 with the reason on stderr.
"""
import argparse
import os
import re
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time

import numpy as np


def free_display():
    for n in range(90, 200):
        if not os.path.exists("/tmp/.X%d-lock" % n) and not os.path.exists("/tmp/.X11-unix/X%d" % n):
            return n
    raise RuntimeError("no free X display number between :90 and :199")


def read_xwd(path):
    """An XWD (X Window Dump) file of a 24/32-bit TrueColor screen as an
    (h, w, 3) uint8 array."""
    with open(path, "rb") as f:
        data = f.read()
    fields = struct.unpack(">25I", data[:100])
    header_size, _version, _fmt, depth, width, height = fields[:6]
    byte_order, bits_per_pixel, bytes_per_line = fields[7], fields[11], fields[12]
    red_mask, green_mask, blue_mask = fields[14], fields[15], fields[16]
    ncolors = fields[19]
    if bits_per_pixel not in (24, 32) or depth not in (24, 32):
        raise RuntimeError("unsupported XWD: %d bits per pixel, depth %d" % (bits_per_pixel, depth))
    size = bits_per_pixel // 8
    start = header_size + 12 * ncolors
    raw = np.frombuffer(data[start:start + bytes_per_line * height], dtype=np.uint8)
    raw = raw.reshape(height, bytes_per_line)[:, :size * width].reshape(height, width, size)
    raw = raw.astype(np.uint32)
    order = range(size) if byte_order == 0 else range(size - 1, -1, -1)  # 0: LSB first
    pixels = np.zeros((height, width), dtype=np.uint32)
    for shift, k in enumerate(order):
        pixels |= raw[:, :, k] << (8 * shift)

    def channel(mask):
        shift = (mask & -mask).bit_length() - 1
        return ((pixels & mask) >> shift).astype(np.uint8)

    return np.dstack([channel(red_mask), channel(green_mask), channel(blue_mask)])


# Mesa's software GL (Xvfb has no other) refuses to link rviz's palette shader
# for the Map display ("indexed_8bit_image ... active samplers with a
# different type refer to the same texture image unit"; reported upstream for
# rviz on Mesa, e.g. ros2/rviz#1279). rviz then draws the map with its
# fallback material: the screenshot shows it. It is reported, not counted.
KNOWN_SOFTWARE_GL = re.compile(r"indexed_8bit_image")

ERROR_PATTERN = re.compile(r"\[ERROR\]|failed to load|PluginlibFactory|Segmentation fault|"
                           r"Could not load|error while loading", re.IGNORECASE)


def pause_player(service, pause):
    import rospy
    from std_srvs.srv import SetBool
    rospy.wait_for_service(service, 10.0)
    rospy.ServiceProxy(service, SetBool)(pause)


def wait_for_clock(at, pause_service, rviz):
    """Blocks until /clock reaches `at` (or rviz exits); then pauses the
    player when a service is named. True when it paused it."""
    import rospy
    from rosgraph_msgs.msg import Clock
    rospy.init_node("rviz_screenshot_clock", anonymous=True, disable_signals=True)
    reached = []
    sub = rospy.Subscriber("/clock", Clock, lambda m: reached.append(True)
                           if m.clock.to_sec() >= at and not reached else None)
    while not reached and rviz.poll() is None:
        time.sleep(0.05)
    sub.unregister()
    if not reached or not pause_service:
        return False
    pause_player(pause_service, True)
    return True


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--config", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--wait", type=float, default=20.0, help="s of rendering before the shot")
    parser.add_argument("--size", default="1400x900")
    parser.add_argument("--at-clock", type=float, default=None,
                        help="log time (s on /clock) to wait for before the --wait")
    parser.add_argument("--pause-service", default="",
                        help="std_srvs/SetBool pausing the bag player while the shot is taken")
    args, _ = parser.parse_known_args([a for a in sys.argv[1:] if not a.startswith("__")])

    for tool in ("Xvfb", "xwd", "rviz"):
        if shutil.which(tool) is None:
            sys.stderr.write("rviz_screenshot: %s not found (make deps installs it)\n" % tool)
            return 1
    display = free_display()
    xvfb = subprocess.Popen(["Xvfb", ":%d" % display, "-screen", "0", args.size + "x24", "-nolisten",
                             "tcp"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    log = tempfile.NamedTemporaryFile(prefix="rviz_", suffix=".log", delete=False)
    rviz = None
    try:
        time.sleep(1.5)
        if xvfb.poll() is not None:
            sys.stderr.write("rviz_screenshot: Xvfb :%d did not start\n" % display)
            return 1
        env = dict(os.environ, DISPLAY=":%d" % display, LIBGL_ALWAYS_SOFTWARE="1")
        rviz = subprocess.Popen(["rviz", "-d", args.config, "__name:=rviz_smoke"], env=env,
                                stdout=log, stderr=subprocess.STDOUT)
        paused = False
        if args.at_clock is not None:
            paused = wait_for_clock(args.at_clock, args.pause_service, rviz)
        deadline = time.time() + args.wait
        while time.time() < deadline:
            if rviz.poll() is not None:
                break
            time.sleep(0.5)
        alive = rviz.poll() is None
        shot_xwd = args.out + ".xwd"
        subprocess.run(["xwd", "-root", "-silent", "-display", ":%d" % display, "-out", shot_xwd],
                       check=True)
        image = read_xwd(shot_xwd)
        os.unlink(shot_xwd)
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.image
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        matplotlib.image.imsave(args.out, image)
    finally:
        if args.at_clock is not None and paused:
            pause_player(args.pause_service, False)
        if rviz is not None and rviz.poll() is None:
            rviz.send_signal(signal.SIGINT)
            try:
                rviz.wait(10)
            except subprocess.TimeoutExpired:
                rviz.kill()
        xvfb.terminate()
        xvfb.wait()
        log.close()
    with open(log.name, errors="replace") as f:
        output = f.read()
    errors, known = [], []
    for line in output.splitlines():
        if ERROR_PATTERN.search(line):
            (known if KNOWN_SOFTWARE_GL.search(line) else errors).append(line)
    colours = len(np.unique(image.reshape(-1, 3)[::7], axis=0))
    print("rviz_screenshot: %s written (%dx%d, %d distinct colours); rviz %s; %d error line(s)" %
          (args.out, image.shape[1], image.shape[0], colours,
           "ran the whole %.0f s" % args.wait if alive else "EXITED EARLY", len(errors)))
    for line in errors:
        print("  rviz: " + line)
    for line in known:
        print("  rviz (known Mesa software-GL shader message, not counted): " + line.strip())
    if not alive:
        sys.stderr.write("rviz_screenshot: rviz exited early; its output:\n" + output[-3000:])
        return 1
    return 0 if not errors else 1


if __name__ == "__main__":
    sys.exit(main())
