import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

from rosgraph_fixture import RosGraph, require_ros  # noqa: E402


@pytest.fixture(scope="session")
def ros_cache(tmp_path_factory):
    return tmp_path_factory.mktemp("aplan_msgs")


@pytest.fixture
def ros(tmp_path, ros_cache):
    """A running ROS master on a free loopback port; stopped after the test with every node."""
    require_ros()
    graph = RosGraph(tmp_path, ros_cache)
    graph.start_master()
    try:
        yield graph
    finally:
        graph.stop()
