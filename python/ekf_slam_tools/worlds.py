"""The simulator's worlds: their polygon descriptions (config/worlds/*.pgm +
*.yaml are drawn from them by tools/dev/make_worlds.py, so the images are
reproducible and reviewable as code), and readers of map_server images.

Worlds:
  carton_layout  thesis §5.1.2: cardboard cartons (0.5 m x 0.35 m) along a
                 straight 5 m x 3.5 m test area, inside a 7 m x 5.5 m room.
  office         an office floor (20 m x 12 m): a corridor loop around a
                 block of rooms, doors into the rooms, furniture, so that a
                 robot can drive a loop and close it. Furniture square to
                 the walls.
  office_turned  the same with the cabinet in the top corridor and three
                 desks turned against the raster (the earlier office:
                 docs/results.md, "The pose NEES").
  calibration_room  a room with a box corner ahead of the start, for the
                 laser-mount calibration tools (docs/bringup.md).
  rooms          six rooms behind 1 m doors on either side of a corridor
                 (16 m x 9 m), for exploration room by room (thesis §4.4;
                 ROOMS gives their extents).
Each YAML carries `start_pose: [x, y, yaw]`, a free pose for the robot
(map_server ignores the extra key).
"""
import math
import os

import numpy as np
import yaml

RESOLUTION = 0.05
WALL = 0.10  # m, wall thickness drawn


def box(cx, cy, w, h, angle=0.0):
    c, s = math.cos(angle), math.sin(angle)
    pts = [(-w / 2, -h / 2), (w / 2, -h / 2), (w / 2, h / 2), (-w / 2, h / 2)]
    return [(cx + c * x - s * y, cy + s * x + c * y) for x, y in pts]


def closed(pts):
    return [(pts[i], pts[(i + 1) % len(pts)]) for i in range(len(pts))]


def carton_layout():
    segments = closed([(-1.0, -1.0), (6.0, -1.0), (6.0, 4.5), (-1.0, 4.5)])
    cartons = [(0.5, 0.4, 0.0), (1.6, 0.3, 0.3), (2.8, 0.5, 0.0), (4.0, 0.35, -0.4),
               (0.9, 3.1, 0.2), (2.2, 3.2, 0.0), (3.4, 3.0, 0.5), (4.6, 3.15, 0.0),
               (5.2, 1.75, 0.785)]
    for x, y, a in cartons:
        segments += closed(box(x, y, 0.5, 0.35, a))
    return segments, (7.5, 6.0), (-1.25, -1.25), (0.0, 1.75, 0.0)


def office(turned=False):
    segments = closed([(0, 0), (20, 0), (20, 12), (0, 12)])  # outer walls
    # Inner block of rooms between the corridors (corridor 2 m wide).
    segments += closed([(2, 2), (18, 2), (18, 10), (2, 10)])
    # Room dividers inside the block, and doors (gaps) onto the corridor.
    for x in (6, 10, 14):
        segments += [((x, 2), (x, 5.5)), ((x, 6.5), (x, 10))]
    segments += [((2, 6), (5, 6)), ((15, 6), (18, 6))]
    # Cut doors into the block's walls by replacing them with pieces.
    segments = [s for s in segments if s not in (((2, 2), (18, 2)), ((18, 10), (2, 10)))]
    for a, b in [(2, 3.5), (4.5, 7.5), (9.0, 11.5), (13.0, 16.5), (17.5, 18)]:
        segments.append(((a, 2), (b, 2)))
    for a, b in [(18, 16.0), (14.5, 12.0), (10.5, 8.0), (6.5, 3.0), (2.5, 2)]:
        segments.append(((a, 10), (b, 10)))
    # Furniture: cabinets and pillars along the corridor, desks in the rooms,
    # all square to the walls. A box turned against the 5 cm raster becomes a
    # staircase whose corners and edges move by centimetres with the
    # viewpoint, which no real cabinet does: their sightings were 10-50 times
    # more often beyond the 99.9 % gate than any other's, and both loops lost
    # among 54 noise seeds lost their heading at the one that stood turned in
    # the top corridor (docs/results.md, "The pose NEES"). `turned` gives that earlier
    # world (office_turned), kept to reproduce it and to try remedies such
    # as features.point_model_sigma on; the carton layout is turned too.
    for x, y, w, h, a in [(0.4, 6.0, 0.5, 1.2, 0), (19.5, 4.0, 0.6, 0.8, 0),
                          (10.0, 0.35, 1.2, 0.4, 0), (7.0, 11.6, 0.8, 0.5, 0),
                          (15.0, 11.6, 0.5, 0.5, 0.3), (4.0, 4.0, 1.2, 0.7, 0.2),
                          (8.0, 8.0, 1.0, 0.6, -0.3), (12.0, 4.0, 0.8, 0.8, 0.6),
                          (16.0, 8.0, 1.2, 0.6, 0)]:
        segments += closed(box(x, y, w, h, a if turned else 0.0))
    return segments, (21.0, 13.0), (-0.5, -0.5), (1.0, 1.0, 0.0)


def office_turned():
    return office(turned=True)


def calibration_room():
    """An 8 m x 6 m room for the laser-mount calibration tools: a 1 m box
    square to the raster whose convex corner stands 1.5 m ahead and 0.87 m
    to the left of the start (30 degrees), so that both its faces stay well
    in view while the robot drives 0.5 m towards it and turns by 30 degrees
    either way, and two more boxes for the scan matcher."""
    segments = closed([(-2.0, -3.0), (6.0, -3.0), (6.0, 3.0), (-2.0, 3.0)])
    for x, y, w, h in [(2.0, 1.37, 1.0, 1.0), (4.5, -1.5, 0.8, 0.5), (-1.0, 2.0, 0.6, 0.6)]:
        segments += closed(box(x, y, w, h))
    return segments, (8.5, 6.5), (-2.25, -3.25), (0.0, 0.0, 0.0)


# The rooms world's corridor: y from 3.5 to 5.5 m, x from 0 to 16 m.
ROOMS_CORRIDOR = (0.0, 3.5, 16.0, 5.5)


def rooms_layout():
    """Named extents (x0, y0, x1, y1) of the rooms world's rooms and its
    corridor (world frame), inside the walls."""
    out = {"corridor": ROOMS_CORRIDOR}
    for i, (x0, x1) in enumerate(((0.0, 5.0), (5.0, 10.5), (10.5, 16.0))):
        out["south %d" % (i + 1)] = (x0, 0.0, x1, 3.5)
        out["north %d" % (i + 1)] = (x0, 5.5, x1, 9.0)
    return out


def rooms():
    """Six rooms behind doors off a corridor: a 16 m x 9 m floor, the
    corridor 2 m wide along its middle, three rooms 3.5 m deep on either
    side, each with a 1 m door onto the corridor (north and south doors
    staggered) and a piece of furniture square to the walls."""
    segments = closed([(0, 0), (16, 0), (16, 9), (0, 9)])
    doors = {"south": [(2.0, 3.0), (8.5, 9.5), (13.5, 14.5)],
             "north": [(3.0, 4.0), (7.0, 8.0), (12.0, 13.0)]}
    for y, side in ((3.5, "south"), (5.5, "north")):
        x = 0.0
        for a, b in doors[side]:
            segments.append(((x, y), (a, y)))
            x = b
        segments.append(((x, y), (16.0, y)))
    for x in (5.0, 10.5):  # the rooms' partitions
        segments += [((x, 0), (x, 3.5)), ((x, 5.5), (x, 9))]
    for x, y, w, h in [(1.0, 1.0, 1.0, 0.6), (7.5, 1.2, 0.8, 0.8), (14.5, 0.8, 1.2, 0.5),
                       (1.5, 7.8, 0.8, 0.6), (9.0, 8.0, 1.2, 0.6), (14.0, 7.5, 0.6, 0.6)]:
        segments += closed(box(x, y, w, h))
    return segments, (16.5, 9.5), (-0.25, -0.25), (1.0, 4.5, 0.0)


def rasterise(segments, size, origin):
    width = int(round(size[0] / RESOLUTION))
    height = int(round(size[1] / RESOLUTION))
    pixels = bytearray([254]) * (width * height)
    half = int(round(WALL / 2 / RESOLUTION))
    for (ax, ay), (bx, by) in segments:
        length = math.hypot(bx - ax, by - ay)
        steps = max(1, int(length / (RESOLUTION / 4)))
        for k in range(steps + 1):
            x = ax + (bx - ax) * k / steps
            y = ay + (by - ay) * k / steps
            ix = int(math.floor((x - origin[0]) / RESOLUTION))
            iy = int(math.floor((y - origin[1]) / RESOLUTION))
            for dx in range(-half, half + 1):
                for dy in range(-half, half + 1):
                    px, py = ix + dx, iy + dy
                    if 0 <= px < width and 0 <= py < height:
                        pixels[(height - 1 - py) * width + px] = 0
    return width, height, bytes(pixels)


def write(out_dir, name, world):
    segments, size, origin, start = world
    width, height, pixels = rasterise(segments, size, origin)
    with open(os.path.join(out_dir, name + ".pgm"), "wb") as f:
        f.write(b"P5\n# generated by tools/dev/make_worlds.py\n%d %d\n255\n" % (width, height))
        f.write(pixels)
    with open(os.path.join(out_dir, name + ".yaml"), "w") as f:
        f.write("# generated by tools/dev/make_worlds.py; map_server format\n")
        f.write("image: %s.pgm\nresolution: %.3f\norigin: [%.3f, %.3f, 0.0]\n" %
                (name, RESOLUTION, origin[0], origin[1]))
        f.write("negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n")
        f.write("start_pose: [%.3f, %.3f, %.3f]\n" % start)
    print("wrote %s (%d x %d cells)" % (name, width, height))


WORLDS = {"carton_layout": carton_layout, "office": office, "office_turned": office_turned,
          "calibration_room": calibration_room, "rooms": rooms}


def read_pgm(path):
    with open(path, "rb") as f:
        data = f.read()
    # Header: magic, optional comments, width height, maxval, then bytes.
    fields, pos = [], 0
    while len(fields) < 4:
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        fields.append(data[pos:end])
        pos = end
    pos += 1
    width, height = int(fields[1]), int(fields[2])
    return np.frombuffer(data[pos:pos + width * height], dtype=np.uint8).reshape(height, width)


def world_vertices(world):
    """Corners of the world's polygons (world frame)."""
    segments = WORLDS[world]()[0]
    vertices = set()
    for a, b in segments:
        vertices.add((round(a[0], 3), round(a[1], 3)))
        vertices.add((round(b[0], 3), round(b[1], 3)))
    return sorted(vertices)


def read_world_grid(yaml_path):
    """A map_server world as (occupied, resolution, origin x, origin y):
    occupied[row, col] is True for a wall cell, row 0 at the bottom (y =
    origin y), so cell (row, col) spans x = ox + col * res, y = oy + row * res."""
    with open(yaml_path) as f:
        meta = yaml.safe_load(f)
    pixels = read_pgm(os.path.join(os.path.dirname(yaml_path), meta["image"]))
    return (pixels < 128)[::-1, :], float(meta["resolution"]), meta["origin"][0], meta["origin"][1]


def read_world_image(yaml_path):
    """Occupied cell centres (world frame) of a map_server world."""
    occupied, res, ox, oy = read_world_grid(yaml_path)
    rows, cols = np.nonzero(occupied)
    return ox + (cols + 0.5) * res, oy + (rows + 0.5) * res
