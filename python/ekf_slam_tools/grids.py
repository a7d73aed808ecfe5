"""Geometry on nav_msgs/OccupancyGrid messages (the simulator's
ground_truth/world, the SLAM map) for tests and tools: ray casting and the
clearance of a point to the nearest occupied cell."""
import math

from ekf_slam_tools.se2 import yaw_of


def ray_cast(grid, origin, angle, max_range, step=0.01):
    """Distance from origin (map frame) along angle to the first occupied cell."""
    info = grid.info
    ox, oy = info.origin.position.x, info.origin.position.y
    oyaw = yaw_of(info.origin.orientation)
    c, s = math.cos(-oyaw), math.sin(-oyaw)
    dx, dy = math.cos(angle), math.sin(angle)
    r = 0.0
    while r < max_range:
        x, y = origin[0] + r * dx - ox, origin[1] + r * dy - oy
        gx, gy = c * x - s * y, s * x + c * y  # into the grid's own axes
        ix, iy = int(math.floor(gx / info.resolution)), int(math.floor(gy / info.resolution))
        if not (0 <= ix < info.width and 0 <= iy < info.height):
            return r
        if grid.data[iy * info.width + ix] >= 50:
            return r
        r += step
    return float("inf")


def clearance(grid, point, search):
    """Distance from point (map frame) to the nearest occupied cell, up to search."""
    info = grid.info
    oyaw = yaw_of(info.origin.orientation)
    c, s = math.cos(-oyaw), math.sin(-oyaw)
    x, y = point[0] - info.origin.position.x, point[1] - info.origin.position.y
    gx, gy = c * x - s * y, s * x + c * y
    res = info.resolution
    nearest = search
    for iy in range(int(math.floor((gy - search) / res)), int(math.floor((gy + search) / res)) + 1):
        for ix in range(int(math.floor((gx - search) / res)), int(math.floor((gx + search) / res)) + 1):
            inside = 0 <= ix < info.width and 0 <= iy < info.height
            if inside and grid.data[iy * info.width + ix] < 50:
                continue
            dx = gx - min(max(gx, ix * res), (ix + 1) * res)
            dy = gy - min(max(gy, iy * res), (iy + 1) * res)
            nearest = min(nearest, math.hypot(dx, dy))
    return nearest


def range_errors(grid, laser, scan, max_range=8.0, reach=7.5):
    """|measured - expected| of each return of a LaserScan taken from the
    pose `laser` (x, y, yaw in the grid's frame), the expected ranges ray
    cast in `grid` up to max_range; beams whose wall lies beyond `reach` are
    left out. Sorted ascending."""
    errors = []
    for i, measured in enumerate(scan.ranges):
        if not math.isfinite(measured) or measured >= scan.range_max:
            continue
        angle = laser[2] + scan.angle_min + i * scan.angle_increment
        expected = ray_cast(grid, laser, angle, max_range)
        if math.isfinite(expected) and expected < reach:
            errors.append(abs(measured - expected))
    errors.sort()
    return errors
