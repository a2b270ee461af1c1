"""The cell on ROS 1 (docs/ros.md): the planner as an action client of a robot server, fed by a topic of
detected markers, as in the paper's experiment (Sec. IV).

- :mod:`.system`: makes Debian's ROS 1 Python packages (``rospy``, ``actionlib``) importable from the
  project's virtual environment, or says what to install;
- :mod:`.interfaces`: our messages and action (``aplan_msgs``, the ``.msg`` / ``.action`` files beside this
  module), generated with genpy into a cache folder on first use, no catkin workspace needed;
- :mod:`.images`: ``sensor_msgs/Image`` -> numpy, for the ArUco detector;
- :mod:`.adapters`: the session's observation source and robot over ROS (:class:`RosRobot`, :func:`marker_stream`),
  the belief publisher and the master watch;
- :mod:`.servers`: the vision server (images -> markers) and the stand-in robot server.

Nothing here is imported unless an ``aplan ros*`` command runs, so the rest of APLAN needs no ROS.
"""
