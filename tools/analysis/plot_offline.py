#!/usr/bin/python3
"""Figures of an ekf_slam_offline run, in the manner of the thesis's Chapter 5.

usage: plot_offline.py DIR

Reads DIR/map*.pgm + .yaml, DIR/trajectory_*.txt, DIR/landmarks.yaml and
DIR/first_last_scans.txt; writes
  DIR/fig_map_slam_vs_odometry.png   the grid and path from SLAM vs from odometry
  DIR/fig_first_last_scans.png       first and last scan in each frame (Fig. 5.7)
  DIR/fig_smoothing.png              the grid before and after smoothing (Fig. 5.11)

Drawn with Pillow straight onto the pixels: the runner calls this after
every run, and matplotlib's import and layout alone took longer than
reading the Intel log (about 1.2 s against 0.2 s here).
"""
import math
import os
import sys

import numpy as np
import yaml
from PIL import Image, ImageDraw, ImageFont

from ekf_slam_tools.worlds import read_pgm

# libyaml's loader where PyYAML has it: a tenth of the pure-Python one's time.
YamlLoader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)

BLUE, GREEN, RED = (31, 119, 180), (44, 160, 44), (214, 39, 40)
PANEL = 600          # px, side of a panel's plotting area
MARGIN_LEFT, MARGIN_BOTTOM, MARGIN_TOP, MARGIN_RIGHT = 62, 46, 30, 18


def font(size):
    """DejaVu Sans where it can be found (matplotlib's copy or the system's)."""
    for path in ["/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
                 "/usr/share/matplotlib/mpl-data/fonts/ttf/DejaVuSans.ttf"]:
        if os.path.exists(path):
            return ImageFont.truetype(path, size)
    return ImageFont.load_default()


FONT, SMALL = font(13), font(11)


def put_text(draw, xy, text, face, anchor="la", fill="black"):
    """Text placed by anchor (horizontal l/m/r, vertical a/t/m/d), with any font."""
    left, top, right, bottom = draw.textbbox((0, 0), text, font=face)
    x = xy[0] - {"l": left, "m": (left + right) / 2, "r": right}[anchor[0]]
    y = xy[1] - {"a": 0, "t": top, "m": (top + bottom) / 2, "d": bottom}[anchor[1]]
    draw.text((x, y), text, fill=fill, font=face)


class Panel:
    """A square plotting area showing world rectangle [x0, x1] x [y0, y1] at one
    scale for both axes (the rectangle is widened to fill the square)."""

    def __init__(self, image, left, top, x0, x1, y0, y1):
        self.image, self.draw = image, ImageDraw.Draw(image)
        self.left, self.top = left, top
        span = max(x1 - x0, y1 - y0, 1e-6)
        cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
        self.x0, self.x1 = cx - 0.5 * span, cx + 0.5 * span
        self.y0, self.y1 = cy - 0.5 * span, cy + 0.5 * span
        self.scale = PANEL / span  # px per m

    def px(self, x, y):
        """Pixel coordinates (arrays or numbers) of world points."""
        return (self.left + (np.asarray(x) - self.x0) * self.scale,
                self.top + (self.y1 - np.asarray(y)) * self.scale)

    def map_image(self, out_dir, base):
        """The occupancy grid under the plotting area, resampled to its pixels."""
        meta = yaml.load(open(os.path.join(out_dir, base + ".yaml")), Loader=YamlLoader)
        grid = read_pgm(os.path.join(out_dir, meta["image"]))
        res = float(meta["resolution"])
        ox, oy = float(meta["origin"][0]), float(meta["origin"][1])
        h, w = grid.shape
        # Map cells under the area (image rows run from the top, largest y, down),
        # padded with unknown (205) where the area reaches beyond the map.
        c0, c1 = int(math.floor((self.x0 - ox) / res)), int(math.ceil((self.x1 - ox) / res))
        r0, r1 = int(math.floor((self.y0 - oy) / res)), int(math.ceil((self.y1 - oy) / res))
        view = np.full((r1 - r0, c1 - c0), 205, dtype=np.uint8)
        sc0, sc1, sr0, sr1 = max(c0, 0), min(c1, w), max(r0, 0), min(r1, h)
        if sc0 < sc1 and sr0 < sr1:
            view[r1 - sr1:r1 - sr0, sc0 - c0:sc1 - c0] = grid[h - sr1:h - sr0, sc0:sc1]
        # Thin walls survive the reduction: the darkest cell of each block of
        # cells that one pixel covers, then a resample to the exact size.
        block = max(1, int((c1 - c0) / PANEL))
        if block > 1:
            rows, cols = (view.shape[0] // block) * block, (view.shape[1] // block) * block
            view = view[:rows, :cols].reshape(rows // block, block, cols // block,
                                              block).min(axis=(1, 3))
        picture = Image.fromarray(view, mode="L").resize(
            (round((c1 - c0) * res * self.scale), round((r1 - r0) * res * self.scale)),
            Image.BILINEAR)
        left, top = self.px(ox + c0 * res, oy + r1 * res)
        self.image.paste(picture.convert("RGB"), (int(round(left)), int(round(top))))

    def path(self, x, y, color, dashed=False):
        u, v = self.px(x, y)
        points = list(zip(u.tolist(), v.tolist()))
        if not dashed:
            self.draw.line(points, fill=color, width=1)
            return
        # Dashes of about 8 px along the path.
        run, on, piece = 0.0, True, [points[0]]
        for a, b in zip(points, points[1:]):
            run += math.hypot(b[0] - a[0], b[1] - a[1])
            piece.append(b)
            if run >= 8.0:
                if on and len(piece) > 1:
                    self.draw.line(piece, fill=color, width=1)
                run, on, piece = 0.0, not on, [b]
        if on and len(piece) > 1:
            self.draw.line(piece, fill=color, width=1)

    def dots(self, x, y, color, radius=1.5):
        u, v = self.px(x, y)
        for a, b in zip(u.tolist(), v.tolist()):
            self.draw.ellipse([a - radius, b - radius, a + radius, b + radius], fill=color)

    def frame(self, title, grid_lines=False):
        """Blanks what was drawn beyond the area, then the border, ticks, labels and title."""
        d, l, t, r, b = self.draw, self.left, self.top, self.left + PANEL, self.top + PANEL
        width, height = self.image.size
        column = (max(0, l - MARGIN_LEFT), min(width, r + MARGIN_RIGHT))
        for box in [(column[0], 0, column[1], t - 1), (column[0], b + 1, column[1], height),
                    (column[0], 0, l - 1, height), (r + 1, 0, column[1], height)]:
            d.rectangle(box, fill="white")
        step = nice_step(self.x1 - self.x0)
        for axis, lo, hi in [("x", self.x0, self.x1), ("y", self.y0, self.y1)]:
            value = math.ceil(lo / step) * step
            while value <= hi + 1e-9:
                text = "%g" % round(value, 6)
                if isinstance(SMALL, ImageFont.FreeTypeFont):
                    text = text.replace("-", "\u2212")  # a true minus sign
                if axis == "x":
                    u = self.px(value, self.y0)[0]
                    if grid_lines:
                        d.line([(u, t), (u, b)], fill=(225, 225, 225))
                    d.line([(u, b), (u, b + 4)], fill="black")
                    put_text(d, (u, b + 6), text, SMALL, "mt")
                else:
                    v = self.px(self.x0, value)[1]
                    if grid_lines:
                        d.line([(l, v), (r, v)], fill=(225, 225, 225))
                    d.line([(l - 4, v), (l, v)], fill="black")
                    put_text(d, (l - 6, v), text, SMALL, "rm")
                value += step
        d.rectangle([l, t, r, b], outline="black")
        put_text(d, ((l + r) / 2, t - 8), title, FONT, "md")
        put_text(d, ((l + r) / 2, b + 24), "x [m]", FONT, "mt")
        label = Image.new("RGB", (60, 18), "white")
        put_text(ImageDraw.Draw(label), (30, 9), "y [m]", FONT, "mm")
        self.image.paste(label.rotate(90, expand=True), (l - MARGIN_LEFT + 2, int((t + b) / 2) - 30))

    def legend(self, entries):
        """Entries (label, colour, kind) in a box at the upper right: kind 'line' or 'dot'."""
        d = self.draw
        width = max(d.textbbox((0, 0), label, font=SMALL)[2] for label, _, _ in entries) + 40
        right, top = self.left + PANEL - 6, self.top + 6
        d.rectangle([right - width, top, right, top + 16 * len(entries) + 6], fill="white",
                    outline=(190, 190, 190))
        for k, (label, color, kind) in enumerate(entries):
            v = top + 11 + 16 * k
            u = right - width + 6
            if kind == "dot":
                d.ellipse([u + 10, v - 2, u + 14, v + 2], fill=color)
            else:
                d.line([(u, v), (u + 24, v)], fill=color, width=2)
            put_text(d, (u + 30, v), label, SMALL, "lm")


def nice_step(span, ticks=6):
    """1, 2 or 5 times a power of ten, near span / ticks."""
    raw = span / ticks
    power = 10.0 ** math.floor(math.log10(raw))
    return min((m * power for m in (1.0, 2.0, 5.0, 10.0)), key=lambda s: abs(s - raw))


def figure(panels):
    """A white canvas for `panels` side by side and their upper-left corners."""
    width = panels * (MARGIN_LEFT + PANEL + MARGIN_RIGHT)
    image = Image.new("RGB", (width, MARGIN_TOP + PANEL + MARGIN_BOTTOM), "white")
    corners = [(k * (MARGIN_LEFT + PANEL + MARGIN_RIGHT) + MARGIN_LEFT, MARGIN_TOP)
               for k in range(panels)]
    return image, corners


def bounds(x, y, margin):
    return x.min() - margin, x.max() + margin, y.min() - margin, y.max() + margin


def trajectory(out_dir, name):
    return np.atleast_2d(np.loadtxt(os.path.join(out_dir, "trajectory_%s.txt" % name)))


def in_frame_of(traj, first_pose):
    """traj (stamp x y theta rows) moved rigidly so that its first pose is first_pose."""
    d_theta = first_pose[3] - traj[0, 3]
    c, s = np.cos(d_theta), np.sin(d_theta)
    out = traj.copy()
    dx, dy = traj[:, 1] - traj[0, 1], traj[:, 2] - traj[0, 2]
    out[:, 1] = first_pose[1] + c * dx - s * dy
    out[:, 2] = first_pose[2] + s * dx + c * dy
    out[:, 3] = traj[:, 3] + d_theta
    return out


def final_poses(out_dir):
    """What map.pgm was drawn from: the loop-closed trajectory when there is
    one, else the smoothed."""
    if os.path.exists(os.path.join(out_dir, "trajectory_optimized.txt")):
        return "loop-closed"
    return "smoothed"


def map_panel(image, corner, out_dir, base, title, traj, margin=5.0):
    panel = Panel(image, corner[0], corner[1], *bounds(traj[:, 1], traj[:, 2], margin))
    panel.map_image(out_dir, base)
    return panel


def save(image, out_dir, name):
    image.save(os.path.join(out_dir, name), compress_level=1)


def main(out_dir):
    smoothed = trajectory(out_dir, "smoothed")
    filtered = trajectory(out_dir, "filtered")
    odometry = trajectory(out_dir, "odometry")

    image, corners = figure(2)
    slam = map_panel(image, corners[0], out_dir, "map", "", smoothed)
    slam.path(smoothed[:, 1], smoothed[:, 2], BLUE)
    entries = [("smoothed path", BLUE, "line")]
    # The scan-matching front end's own track (the filter's control), when it ran.
    if os.path.exists(os.path.join(out_dir, "trajectory_scan_matched.txt")):
        # It lives in the odometry frame: place its first pose on the smoothed one.
        matched = in_frame_of(trajectory(out_dir, "scan_matched"), smoothed[0])
        slam.path(matched[:, 1], matched[:, 2], GREEN, dashed=True)
        entries.append(("scan-matched control", GREEN, "line"))
    landmarks = yaml.load(open(os.path.join(out_dir, "landmarks.yaml")),
                          Loader=YamlLoader)["landmarks"] or []
    if landmarks:
        slam.dots(np.array([m["x"] for m in landmarks]), np.array([m["y"] for m in landmarks]),
                  RED)
        entries.append(("landmarks", RED, "dot"))
    slam.frame("EKF-SLAM map (%s poses) and smoothed path" % final_poses(out_dir))
    slam.legend(entries)
    wheels = map_panel(image, corners[1], out_dir, "map_odometry", "", odometry)
    wheels.path(odometry[:, 1], odometry[:, 2], RED)
    wheels.frame("odometry only")
    save(image, out_dir, "fig_map_slam_vs_odometry.png")

    rows = [line.split() for line in open(os.path.join(out_dir, "first_last_scans.txt"))
            if not line.startswith("#")]
    image, corners = figure(2)
    for corner, frame in zip(corners, ["odometry", "slam"]):
        scans = {which: np.array([[float(r[2]), float(r[3])] for r in rows
                                  if r[0] == frame and r[1] == which]).reshape(-1, 2)
                 for which in ["first", "last"]}
        every = np.vstack([scans["first"], scans["last"]])
        if not len(every):
            every = np.zeros((1, 2))
        panel = Panel(image, corner[0], corner[1], *bounds(every[:, 0], every[:, 1], 1.0))
        panel.frame("first and last scan placed with %s poses" % frame, grid_lines=True)
        for which, color in [("first", BLUE), ("last", RED)]:
            if len(scans[which]):
                panel.dots(scans[which][:, 0], scans[which][:, 1], color, radius=1.0)
        panel.legend([("first scan", BLUE, "dot"), ("last scan", RED, "dot")])
    save(image, out_dir, "fig_first_last_scans.png")

    image, corners = figure(2)
    before = map_panel(image, corners[0], out_dir, "map_filtered", "", filtered)
    after = map_panel(image, corners[1], out_dir, "map", "", smoothed)
    before.frame("grid from the filtered poses")
    after.frame("grid from the %s poses" % final_poses(out_dir))
    save(image, out_dir, "fig_smoothing.png")
    print("figures written to " + out_dir)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
