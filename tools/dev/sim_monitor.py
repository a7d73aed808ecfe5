#!/usr/bin/python3
"""Watches a simulated SLAM run and scores it against the simulator's ground
truth (make demo, test/sim_office_loop.test): ekf_slam_tools.sim_monitor.

usage (as a ROS node): sim_monitor.py --out DIR [--world office] [--timeout S]
"""
from ekf_slam_tools.sim_monitor import main

if __name__ == "__main__":
    main()
