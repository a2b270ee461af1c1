"""aplan_msgs generated from our .msg / .action files with genpy (no catkin), and sensor_msgs/Image -> numpy."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from planner.runtime.ros.images import ENCODINGS, ImageError, image_to_array
from rosgraph_fixture import ros_cache  # noqa: F401 - fixture


def _image(frame: np.ndarray, encoding: str, pad: int = 0):
    height, width = frame.shape[:2]
    rows = frame.reshape(height, -1)
    step = rows.shape[1] + pad
    data = np.zeros((height, step), np.uint8)
    data[:, :rows.shape[1]] = rows
    return SimpleNamespace(encoding=encoding, height=height, width=width, step=step, data=data.tobytes())


def test_images_of_every_readable_encoding_become_the_detectors_frame():
    rng = np.random.default_rng(1)
    bgr = rng.integers(0, 256, (5, 7, 3), dtype=np.uint8)
    assert np.array_equal(image_to_array(_image(bgr, "bgr8", pad=3)), bgr)
    assert np.array_equal(image_to_array(_image(bgr[:, :, ::-1].copy(), "rgb8")), bgr)
    rgba = np.concatenate([bgr[:, :, ::-1], np.full((5, 7, 1), 9, np.uint8)], axis=2)
    assert np.array_equal(image_to_array(_image(rgba, "rgba8", pad=1)), bgr)
    grey = bgr[:, :, 0].copy()
    assert np.array_equal(image_to_array(_image(grey, "mono8", pad=5)), grey)
    assert set(ENCODINGS) >= {"bgr8", "rgb8", "mono8"}


def test_an_image_the_detector_cannot_read_is_a_clear_error():
    grey = np.zeros((4, 4), np.uint8)
    with pytest.raises(ImageError, match="encoding 'bayer_rggb8' cannot be read by the marker detector"):
        image_to_array(_image(grey, "bayer_rggb8"))
    short = _image(grey, "mono8")
    short.data = short.data[:-1]
    with pytest.raises(ImageError, match="holds 15 bytes, not the 16 it needs"):
        image_to_array(short)


def test_the_messages_and_the_action_are_generated_with_genpy(ros_cache, monkeypatch):
    from rosgraph_fixture import require_ros

    require_ros()
    monkeypatch.setenv("APLAN_ROS_CACHE", str(ros_cache))
    from planner.runtime.ros.interfaces import messages

    msgs = messages()
    # actionlib's convention: the seven messages of Perform, with the standard header, goal id and status
    assert msgs.PerformActionGoal._slot_types == ["std_msgs/Header", "actionlib_msgs/GoalID", "aplan_msgs/PerformGoal"]
    assert msgs.PerformActionResult._slot_types == ["std_msgs/Header", "actionlib_msgs/GoalStatus",
                                                    "aplan_msgs/PerformResult"]
    assert msgs.PerformAction.__slots__ == ["action_goal", "action_result", "action_feedback"]
    assert msgs.PerformResult.__slots__ == ["done", "reason"]
    assert msgs.Markers.__slots__ == ["header", "frame", "ids", "error"]
    assert msgs.Belief._slot_types[3] == "aplan_msgs/Intention[]"
    # what a ROS tool checks when a node connects: the md5 genmsg computes from the definitions
    from genmsg import MsgContext
    from genmsg.gentools import compute_md5
    from genmsg.msg_loader import load_msg_by_type, load_depends

    from planner.runtime.ros.interfaces import _SEARCH, _sources

    context = MsgContext.create_default()
    search = {"aplan_msgs": [str(ros_cache / "defs")], **{k: [str(v)] for k, v in _SEARCH.items()}}
    (ros_cache / "defs").mkdir(exist_ok=True)
    for name, text in _sources().items():
        (ros_cache / "defs" / f"{name}.msg").write_text(text)
    spec = load_msg_by_type(context, "aplan_msgs/PerformActionGoal", search)
    load_depends(context, spec, search)
    assert compute_md5(context, spec) == msgs.PerformActionGoal._md5sum
