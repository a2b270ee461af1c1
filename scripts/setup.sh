#!/usr/bin/env bash
# Set up APLAN in ./.venv (idempotent). With --freecad, also install Debian's FreeCAD 0.20 (headless
# freecadcmd, the GUI and Xvfb) and the Python packages FreeCAD's own interpreter needs, when they are
# missing and apt can be used (as root, or through passwordless sudo). FreeCAD's own Python gets Debian's
# numpy, networkx, lxml, scipy, matplotlib, jsonschema and threadpoolctl (the planner, the occt engine, solving,
# pictures);
# the mesh engine's trimesh and manifold3d are not packaged by Debian, so the workbench runs that engine in
# this .venv. With --ros (or --freecad --ros), also install Debian's ROS 1 (rosmaster, rospy, actionlib, genpy and
# the standard message definitions; aplan ros, docs/ros.md) when missing, and generate aplan_msgs.
set -euo pipefail
cd "$(dirname "$0")/.."

if [ ! -x .venv/bin/python ]; then
    python3 -m venv .venv
fi
# --no-cache-dir: the wheels are not kept a second time in ~/.cache/pip (a CI disk can be nearly full).
.venv/bin/python -m pip install --quiet --disable-pip-version-check --no-cache-dir -e '.[test]'

# Debian's FreeCAD runs the system Python 3: it needs these modules too (also where FreeCAD is installed already).
freecad_ready() {
    command -v freecadcmd >/dev/null 2>&1 && command -v xvfb-run >/dev/null 2>&1 &&
        /usr/bin/python3 -c "import numpy, networkx, lxml, scipy, matplotlib, jsonschema, threadpoolctl" 2>/dev/null
}

want_freecad=0; want_ros=0
for option in "$@"; do
    case "$option" in
        --freecad) want_freecad=1 ;;
        --ros) want_ros=1 ;;
        *) echo "setup: unknown option $option (use --freecad, --ros)" >&2; exit 2 ;;
    esac
done
if [ "$(id -u)" = 0 ]; then as_root=(); elif sudo -n true 2>/dev/null; then as_root=(sudo -n); else as_root=(); fi
# apt keeps no copy of the packages it downloads here (APT::Keep-Downloaded-Packages=false: several hundred MB
# on a disk that may have little to spare); packages already in its cache are left alone.
apt_install() {
    DEBIAN_FRONTEND=noninteractive "${as_root[@]}" apt-get install -y -qq --no-install-recommends \
        -o APT::Keep-Downloaded-Packages=false "$@" >/dev/null
}
can_apt() { command -v apt-get >/dev/null 2>&1 && { [ "$(id -u)" = 0 ] || [ ${#as_root[@]} -gt 0 ]; }; }

if [ "$want_freecad" = 1 ] && ! freecad_ready; then
    if can_apt; then
        echo "setup: installing FreeCAD and its Python packages from Debian (about a minute)" >&2
        "${as_root[@]}" apt-get update -qq
        apt_install freecad-python3 freecad xvfb xauth python3-numpy python3-networkx python3-lxml python3-scipy \
            python3-matplotlib python3-jsonschema python3-threadpoolctl
    else
        echo "setup: FreeCAD (or a Python package it needs) is missing and apt-get cannot be used here: FreeCAD tests will be skipped" >&2
    fi
fi

# ROS 1 for the system Python (the .venv reaches it: planner/runtime/ros/system.py); no recommends, to stay small.
ros_ready() {
    command -v rosmaster >/dev/null 2>&1 && [ -d /usr/share/std_msgs/msg ] && [ -d /usr/share/actionlib_msgs/msg ] &&
        /usr/bin/python3 -c "import rospy, actionlib, genpy, sensor_msgs.msg" 2>/dev/null
}
if [ "$want_ros" = 1 ]; then
    if ! ros_ready; then
        if can_apt; then
            echo "setup: installing ROS 1 from Debian (rosmaster, rospy, actionlib, genpy)" >&2
            "${as_root[@]}" apt-get update -qq
            apt_install ros-core python3-rospy python3-actionlib python3-actionlib-msgs python3-sensor-msgs \
                python3-genpy python3-genmsg ros-std-msgs ros-actionlib-msgs
        else
            echo "setup: ROS 1 is missing and apt-get cannot be used here: ROS tests will be skipped" >&2
        fi
    fi
    if ros_ready; then
        .venv/bin/python -c "from planner.runtime.ros.interfaces import generate; print('setup: aplan_msgs in', generate())" >&2
    fi
fi
