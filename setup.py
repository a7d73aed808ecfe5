# The Python tools as one package, ekf_slam_tools (catkin_python_setup()):
# importable from the development and the install space alike.
from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

setup(**generate_distutils_setup(packages=["ekf_slam_tools"], package_dir={"": "python"}))
