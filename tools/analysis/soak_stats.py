#!/usr/bin/python3
"""Prints the figures docs/robustness.md gives for a live soak
(tools/dev/live_soak.py): the resident set at given minutes (the median of
the samples within 30 s of each, which smooths the steps the allocator's
trims make), the least-squares slope of the resident set from a given
minute to the end, and the key scans. Where the soak recorded the node's
heap in use (its last column, newer soaks), the same for it; where it left
live_soak_maps.txt beside the file (where the resident set lies, once a
minute), each kind's value at the given minutes and its slope.

usage: tools/analysis/soak_stats.py output/soak_loops/live_soak.txt [more files]
           [--minutes 5 20 29] [--slope-from 20]
"""
import argparse
import os
import statistics

MAP_KINDS = ("main arena [heap]", "further arenas", "other anonymous", "stacks", "files")


def load(path):
    """(t [s], rss [KiB], scans, key scans, key scans without readings,
    heap in use [KiB] or None) per sample."""
    rows = []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            v = line.split()
            heap = int(v[7]) if len(v) > 7 and int(v[7]) > 0 else None
            rows.append((float(v[0]), int(v[1]), int(v[4]), int(v[5]), int(v[6]), heap))
    return rows


def load_maps(path):
    """(t [s], KiB per kind of MAP_KINDS...) per sample of live_soak_maps.txt."""
    rows = []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            v = line.split()
            rows.append((float(v[0]),) + tuple(int(x) for x in v[1:1 + len(MAP_KINDS)]))
    return rows


def print_maps(path, minutes, slope_from):
    rows = load_maps(path)
    if not rows:
        return
    print(f"  where the resident set lies ({os.path.basename(path)}), MiB:")
    picked = []
    for minute in minutes:
        near = [r for r in rows if abs(r[0] - 60.0 * minute) <= 60.0]
        if near:
            picked.append((minute, min(near, key=lambda r: abs(r[0] - 60.0 * minute))))
    late = [r for r in rows if r[0] >= 60.0 * slope_from]
    for k, kind in enumerate(MAP_KINDS, start=1):
        values = ", ".join(f"{minute:g} min {r[k] / 1024.0:.1f}" for minute, r in picked)
        slope = ""
        if len(late) > 1:
            slope = f"; from {slope_from:g} min {slope_mib_per_minute(late, k):.2f} MiB/min"
        print(f"    {kind}: {values}{slope}")


def slope_mib_per_minute(rows, column):
    rows = [r for r in rows if r[column] is not None]
    n = len(rows)
    mean_t = sum(r[0] for r in rows) / n
    mean_v = sum(r[column] for r in rows) / n
    num = sum((r[0] - mean_t) * (r[column] - mean_v) for r in rows)
    den = sum((r[0] - mean_t) ** 2 for r in rows)
    return num / den * 60.0 / 1024.0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("soaks", nargs="+", help="live_soak.txt files")
    parser.add_argument("--minutes", type=float, nargs="+", default=[5.0, 20.0, 29.0])
    parser.add_argument("--slope-from", type=float, default=20.0, help="minute")
    args = parser.parse_args()
    for path in args.soaks:
        rows = load(path)
        if not rows:
            print(f"{path}: no samples")
            continue
        print(path)
        for minute in args.minutes:
            near = [r for r in rows if abs(r[0] - 60.0 * minute) <= 30.0]
            if not near:
                print(f"  {minute:g} min: no samples")
                continue
            at = min(near, key=lambda r: abs(r[0] - 60.0 * minute))
            rss = statistics.median(r[1] for r in near) / 1024.0
            heaps = [r[5] for r in near if r[5] is not None]
            heap = f", heap {statistics.median(heaps) / 1024.0:.1f} MiB" if heaps else ""
            print(f"  {minute:g} min: RSS {rss:.1f} MiB{heap}, {at[2]} scans, {at[3]} key scans "
                  f"({at[3] - at[4]} holding readings)")
        late = [r for r in rows if r[0] >= 60.0 * args.slope_from]
        if len(late) > 1:
            heap = ""
            if sum(r[5] is not None for r in late) > 1:
                heap = f" (heap {slope_mib_per_minute(late, 5):.2f} MiB/min)"
            print(f"  from {args.slope_from:g} min to the end ({late[-1][0] / 60.0:.1f} min): "
                  f"RSS {slope_mib_per_minute(late, 1):.2f} MiB/min{heap}, "
                  f"{late[-1][3] - late[0][3]} key scans added")
        maps = os.path.join(os.path.dirname(path), "live_soak_maps.txt")
        if os.path.exists(maps):
            print_maps(maps, args.minutes, args.slope_from)


if __name__ == "__main__":
    main()
