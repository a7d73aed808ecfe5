#!/usr/bin/python3
"""Live soak: the node runs for a fixed wall-clock time, and its memory and
CPU are logged once a second.

Two drives:
- the simulator (the default): `sim.launch waypoints:=office_loop
  laps:=1000`, the whole stack on pseudo-terminals (emulated P3-DX and
  LMS200, the drivers, ekf_slam_node), lap after lap of the office;
- a recorded log (--bag): `slam.launch` with its shipped configuration
  (loop closure on) and `rosbag play --clock -r RATE`, use_sim_time; the
  robot's own building, revisited as the log revisits it.

Starts its own roscore (port --port), finds the ekf_slam_node process and
samples /proc/<pid>: the resident set (VmRSS) and the CPU time (utime +
stime) of the last second. It also records the node's landmark count, scans
processed and key scans from /diagnostics, so that memory can be set
against what the map explains.

Writes OUT/live_soak.txt (t_s rss_kib cpu_percent landmarks scans_processed key_scans
key_scans_without_readings heap_in_use_kib; the key scans 0 with loop closure off;
heap_in_use_kib is the node's own count of its allocated heap, /diagnostics)
and OUT/live_soak_maps.txt, once a minute, where the resident set lies
(/proc/<pid>/smaps: t_s heap_kib thread_arenas_kib other_anonymous_kib
stacks_kib files_kib anonymous_mappings): the main arena's [heap], the
64 MiB-aligned mappings glibc gives each further arena, the rest of the
anonymous memory (large mmapped chunks, thread stacks without a name),
[stack], and what is mapped from files (code, libraries). It tells pages
the allocator keeps from memory mapped outside it.
Prints a summary: RSS after the warm-up and at the end.

usage (after make build, with the workspace sourced):
  source .build/setup.bash
  tools/dev/live_soak.py --minutes 30 --out output/soak
  tools/dev/live_soak.py --minutes 30 --out output/soak_loops --loop-closure
  tools/dev/live_soak.py --minutes 30 --out output/soak_intel \
      --bag ../shared/datasets/intel.orig.bag
"""
import argparse
import os
import signal
import subprocess
import sys
import time

import rospy
from diagnostic_msgs.msg import DiagnosticArray


def find_node(name, deadline):
    while time.monotonic() < deadline:
        for pid in os.listdir("/proc"):
            if not pid.isdigit():
                continue
            try:
                with open("/proc/%s/cmdline" % pid, "rb") as f:
                    argv = f.read().split(b"\0")
            except OSError:
                continue
            if argv and os.path.basename(argv[0].decode(errors="replace")) == name:
                return int(pid)
        time.sleep(0.5)
    return None


def sample(pid):
    """(rss KiB, cpu seconds) of process pid, or None when it is gone."""
    try:
        with open("/proc/%d/status" % pid) as f:
            rss = next(int(line.split()[1]) for line in f if line.startswith("VmRSS:"))
        with open("/proc/%d/stat" % pid) as f:
            fields = f.read().rsplit(")", 1)[1].split()
        ticks = os.sysconf("SC_CLK_TCK")
        return rss, (int(fields[11]) + int(fields[12])) / ticks
    except (OSError, StopIteration, ValueError):
        return None


ARENA_BYTES = 64 << 20  # glibc's HEAP_MAX_SIZE on 64-bit: one further arena's mapping


def resident_by_kind(pid):
    """(heap, thread arenas, other anonymous, stacks, files, anonymous mappings)
    of process pid in KiB (the last a count), from /proc/<pid>/smaps; None
    when it is gone. A further arena is an anonymous mapping whose start is
    64 MiB-aligned and whose reservation (with the unreadable rest glibc
    keeps next to it) is at most 64 MiB."""
    totals = {"heap": 0, "arena": 0, "anon": 0, "stack": 0, "file": 0}
    mappings = 0
    try:
        with open("/proc/%d/smaps" % pid) as f:
            kind = None
            for line in f:
                fields = line.split()
                if "-" in fields[0] and len(fields) >= 5 and ":" in fields[3]:
                    start, end = (int(v, 16) for v in fields[0].split("-"))
                    name = fields[5] if len(fields) > 5 else ""
                    if name == "[heap]":
                        kind = "heap"
                    elif name.startswith("[stack"):
                        kind = "stack"
                    elif name.startswith("/"):
                        kind = "file"
                    elif name == "":
                        mappings += 1
                        aligned = start % ARENA_BYTES == 0 and end - start <= ARENA_BYTES
                        kind = "arena" if aligned and "r" in fields[1] else "anon"
                    else:
                        kind = None  # [vdso], [vvar], ...
                elif fields[0] == "Rss:" and kind is not None:
                    totals[kind] += int(fields[1])
    except (OSError, ValueError, IndexError):
        return None
    return (totals["heap"], totals["arena"], totals["anon"], totals["stack"], totals["file"],
            mappings)


class Diagnostics:
    def __init__(self):
        self.values = {}
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_message, queue_size=10)

    def on_message(self, msg):
        for status in msg.status:
            if "EKF-SLAM" in status.name:
                self.values = {kv.key: kv.value for kv in status.values}


def loop_closure_config(args):
    """OUT/soak_config.yaml: --config (default the simulator's) with
    loop_closure.enabled set."""
    import rospkg
    import yaml
    source = args.config or os.path.join(rospkg.RosPack().get_path("ekf_slam"), "config",
                                         "ekf_slam_sim.yaml")
    with open(source) as f:
        config = yaml.safe_load(f)
    config.setdefault("loop_closure", {})["enabled"] = True
    path = os.path.join(args.out, "soak_config.yaml")
    with open(path, "w") as f:
        f.write("# %s with loop_closure.enabled: true (tools/dev/live_soak.py --loop-closure)\n"
                % source)
        yaml.safe_dump(config, f, default_flow_style=False)
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--minutes", type=float, default=30.0)
    parser.add_argument("--warmup-minutes", type=float, default=5.0)
    parser.add_argument("--out", default="output/soak")
    parser.add_argument("--port", type=int, default=11473)
    parser.add_argument("--config", default="",
                        help="SLAM parameters for sim.launch (default: its own, the "
                             "simulator's config/ekf_slam_sim.yaml, loop closure off); "
                             "config/ekf_slam_p3dx.yaml soaks the robot's configuration, "
                             "scan matching and loop closure on")
    parser.add_argument("--loop-closure", action="store_true",
                        help="the simulator's configuration with the loop-closing back end "
                             "on (written to OUT/soak_config.yaml): its key scans are what "
                             "grows with the distance driven")
    parser.add_argument("--bag", default="",
                        help="replay this log through slam.launch (its shipped "
                             "configuration, or --config) instead of driving the simulator")
    parser.add_argument("--rate", type=float, default=1.0, help="replay rate with --bag")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    if args.bag and not os.path.exists(args.bag):
        print("live_soak: %s not found" % args.bag, file=sys.stderr)
        return 2
    if args.loop_closure:
        args.config = loop_closure_config(args)
    env = dict(os.environ, ROS_MASTER_URI="http://localhost:%d" % args.port)
    os.environ.update(env)
    log = open(os.path.join(args.out, "live_soak_roslaunch.log"), "w")
    procs = [subprocess.Popen(["roscore", "-p", str(args.port)], env=env, stdout=log,
                              stderr=subprocess.STDOUT, start_new_session=True)]
    try:
        time.sleep(3.0)
        config = ["config:=" + os.path.abspath(args.config)] if args.config else []
        if args.bag:
            subprocess.check_call(["rosparam", "set", "use_sim_time", "true"], env=env)
            launch = ["roslaunch", "ekf_slam", "slam.launch", "features:=false"]
        else:
            launch = ["roslaunch", "ekf_slam", "sim.launch", "waypoints:=office_loop",
                      "laps:=1000", "link_dir:=/tmp/ekf_slam_soak"]
        procs.append(subprocess.Popen(launch + config, env=env, stdout=log,
                                      stderr=subprocess.STDOUT, start_new_session=True))
        pid = find_node("ekf_slam_node", time.monotonic() + 60.0)
        if pid is None:
            print("live_soak: ekf_slam_node did not start (see %s)" % log.name, file=sys.stderr)
            return 2
        if args.bag:
            time.sleep(3.0)
            procs.append(subprocess.Popen(
                ["rosbag", "play", "--clock", "--quiet", "-r", str(args.rate), args.bag],
                env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True))
        rospy.init_node("live_soak", anonymous=True, disable_signals=True)
        diagnostics = Diagnostics()
        path = os.path.join(args.out, "live_soak.txt")
        rows = []
        maps = open(os.path.join(args.out, "live_soak_maps.txt"), "w")
        maps.write("# t_s heap_kib thread_arenas_kib other_anonymous_kib stacks_kib files_kib "
                   "anonymous_mappings\n")
        next_maps = 0.0
        with open(path, "w") as out:
            out.write("# t_s rss_kib cpu_percent landmarks scans_processed key_scans "
                      "key_scans_without_readings heap_in_use_kib\n")
            start = time.monotonic()
            last = sample(pid)
            last_t = start
            while time.monotonic() - start < args.minutes * 60.0:
                time.sleep(1.0)
                now = time.monotonic()
                current = sample(pid)
                if current is None:
                    print("live_soak: ekf_slam_node exited after %.0f s" % (now - start),
                          file=sys.stderr)
                    return 1
                cpu = 100.0 * (current[1] - last[1]) / (now - last_t)
                last, last_t = current, now
                values = diagnostics.values
                row = (now - start, current[0], cpu, int(values.get("landmarks", "0") or 0),
                       int(values.get("scans processed", "0") or 0),
                       int(values.get("key scans", "0") or 0),
                       int(values.get("key scans without readings (place full)", "0") or 0),
                       int(values.get("heap in use [KiB]", "0") or 0))
                rows.append(row)
                out.write("%.1f %d %.1f %d %d %d %d %d\n" % row)
                out.flush()
                if now - start >= next_maps:
                    kinds = resident_by_kind(pid)
                    if kinds is not None:
                        maps.write("%.1f %d %d %d %d %d %d\n" % ((now - start,) + kinds))
                        maps.flush()
                    next_maps += 60.0
        warm = [r for r in rows if r[0] >= args.warmup_minutes * 60.0]
        if not warm:
            print("live_soak: shorter than the warm-up; nothing to compare", file=sys.stderr)
            return 1
        cpu_mean = sum(r[2] for r in rows) / len(rows)
        print("live soak: %.1f min, %d scans processed, %d landmarks at the end, "
              "%d key scans (%d without readings)" %
              (rows[-1][0] / 60.0, rows[-1][4], rows[-1][3], rows[-1][5], rows[-1][6]))
        print("RSS %d KiB after the %.0f min warm-up, %d KiB at the end (max %d KiB); "
              "CPU %.1f %% mean" % (warm[0][1], args.warmup_minutes, rows[-1][1],
                                     max(r[1] for r in warm), cpu_mean))
        print("samples: %s" % path)
        return 0
    finally:
        for p in reversed(procs):
            try:
                os.killpg(p.pid, signal.SIGINT)
                p.wait(timeout=20)
            except (OSError, subprocess.TimeoutExpired):
                os.killpg(p.pid, signal.SIGKILL)


if __name__ == "__main__":
    sys.exit(main())
