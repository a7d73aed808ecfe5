#!/usr/bin/python3
"""Draws the simulator's worlds (config/worlds/*.pgm + *.yaml, map_server
format) from their polygon descriptions in ekf_slam_tools.worlds.

usage: make_worlds.py [OUT_DIR]   (default: config/worlds beside this script)
"""
import os
import sys

from ekf_slam_tools import worlds


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "..", "config", "worlds")
    os.makedirs(out_dir, exist_ok=True)
    for name, world in worlds.WORLDS.items():
        worlds.write(out_dir, name, world())


if __name__ == "__main__":
    main()
