"""``sensor_msgs/Image`` <-> numpy, for the ArUco detector (which takes grey or BGR ``uint8`` frames).

Encodings read: ``bgr8``, ``rgb8``, ``bgra8``, ``rgba8``, ``mono8`` (and ``8UC1`` / ``8UC3``, taken as grey and
BGR). Rows may be padded (``step`` > width x channels). Anything else (16-bit, Bayer, compressed) is an
:class:`ImageError` naming the encoding. Done with numpy rather than cv_bridge, whose compiled extension is
built against Debian's numpy 1.x and does not load beside the project's numpy 2.x. Cost: one copy of the
frame.
"""
from __future__ import annotations

import numpy as np

from ...errors import PlannerError

__all__ = ["ENCODINGS", "ImageError", "image_to_array", "array_to_image"]

ENCODINGS = {"bgr8": 3, "rgb8": 3, "bgra8": 4, "rgba8": 4, "mono8": 1, "8UC1": 1, "8UC3": 3}


class ImageError(PlannerError):
    """A ``sensor_msgs/Image`` the detector cannot read."""


def image_to_array(message) -> np.ndarray:
    """The frame of ``message`` as ``(H, W)`` (grey) or ``(H, W, 3)`` BGR ``uint8``."""
    encoding = message.encoding
    channels = ENCODINGS.get(encoding)
    if channels is None:
        raise ImageError(f"image encoding {encoding!r} cannot be read by the marker detector; publish one of "
                         f"{', '.join(ENCODINGS)} (e.g. through image_proc)")
    height, width, step = int(message.height), int(message.width), int(message.step)
    data = message.data
    if height <= 0 or width <= 0 or step < width * channels or len(data) < height * step:
        raise ImageError(f"image of {width}x{height} {encoding} with step {step} holds {len(data)} bytes, "
                         f"not the {height * step} it needs")
    buffer = np.frombuffer(data if isinstance(data, (bytes, bytearray)) else bytes(data), np.uint8)
    rows = buffer[:height * step].reshape(height, step)[:, :width * channels]
    frame = rows.reshape(height, width, channels) if channels > 1 else rows.reshape(height, width)
    if encoding in ("rgb8", "rgba8"):
        frame = frame[:, :, 2::-1]  # to BGR, dropping alpha
    elif channels == 4:
        frame = frame[:, :, :3]
    return np.ascontiguousarray(frame)


def array_to_image(frame: np.ndarray, image_class, stamp=None):
    """A ``sensor_msgs/Image`` (``image_class``) of a grey (``mono8``) or BGR (``bgr8``) ``uint8`` frame."""
    frame = np.ascontiguousarray(frame, dtype=np.uint8)
    message = image_class()
    if stamp is not None:
        message.header.stamp = stamp
    message.height, message.width = frame.shape[:2]
    message.encoding = "mono8" if frame.ndim == 2 else "bgr8"
    message.step = frame.shape[1] * (1 if frame.ndim == 2 else frame.shape[2])
    message.data = frame.tobytes()
    return message
