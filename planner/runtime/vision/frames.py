"""Where frames come from: a camera, a video file, a folder of images, each an iterator of ``(H, W, 3)
uint8`` BGR images that raises :class:`~.markers.VisionError` with the cause when it cannot be opened or
read; :func:`in_background` reads any of them in a thread (a live camera keeps being read while the loop
waits for the robot). OpenCV is imported on first use."""
from __future__ import annotations

import queue
import threading
from pathlib import Path
from typing import Iterator

import numpy as np

from .markers import VisionError

__all__ = ["IMAGE_SUFFIXES", "camera_frames", "video_frames", "image_frames", "frames_for", "in_background"]

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp")


def _open_capture(target, what: str, fix: str):
    import cv2

    capture = cv2.VideoCapture(target)
    if not capture.isOpened():
        capture.release()
        raise VisionError(f"{what} cannot be opened; {fix}")
    return capture


def _read_all(capture, what: str, must_read: bool) -> Iterator[np.ndarray]:
    try:
        count = 0
        while True:
            ok, frame = capture.read()
            if not ok or frame is None:
                if count == 0 and must_read:
                    raise VisionError(f"{what} delivers no frames; check the file or device")
                return
            count += 1
            yield frame
    finally:
        capture.release()


def camera_frames(index: int) -> Iterator[np.ndarray]:
    """Frames from camera ``index`` (OpenCV's numbering: /dev/video<index> on Linux) until it stops."""
    capture = _open_capture(index, f"camera {index}",
                            "check the index (ls /dev/video*), the cable, and that no other program uses it")
    return _read_all(capture, f"camera {index}", True)


def video_frames(path: str | Path) -> Iterator[np.ndarray]:
    """The frames of a video file, in order."""
    path = Path(path)
    if not path.is_file():
        raise VisionError(f"{path}: no such video file")
    capture = _open_capture(str(path), f"{path}", "it is not a video OpenCV can decode (try an .mp4 or .avi)")
    return _read_all(capture, str(path), True)


def image_frames(folder: str | Path) -> Iterator[np.ndarray]:
    """The images of ``folder`` (``IMAGE_SUFFIXES``) in file-name order; an unreadable one is an error."""
    import cv2

    folder = Path(folder)
    if not folder.is_dir():
        raise VisionError(f"{folder}: no such folder of images")
    files = sorted(p for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
    if not files:
        raise VisionError(f"{folder}: holds no images ({', '.join(IMAGE_SUFFIXES)})")

    def read() -> Iterator[np.ndarray]:
        for path in files:
            frame = cv2.imread(str(path), cv2.IMREAD_COLOR)
            if frame is None:
                raise VisionError(f"{path}: cannot be read as an image (damaged or not an image); remove or "
                                  "replace it")
            yield frame

    return read()


def frames_for(camera: int | None = None, video: str | None = None, images: str | None = None) -> Iterator[np.ndarray]:
    """The frame source named by exactly one of ``camera``, ``video``, ``images``."""
    chosen = [x is not None for x in (camera, video, images)]
    if sum(chosen) != 1:
        raise VisionError("give exactly one of a camera index, a video file or a folder of images")
    if camera is not None:
        return camera_frames(camera)
    return video_frames(video) if video is not None else image_frames(images)


def in_background(items: Iterator, maxsize: int = 0) -> Iterator:
    """Run ``items`` in a thread and yield what it yields (errors re-raised here), so a live camera keeps
    being read and detected while the loop waits for the robot; closing the iterator stops the thread.
    ``maxsize``: the most items waiting (0: no limit)."""
    channel: queue.Queue = queue.Queue(maxsize)
    stop = threading.Event()
    done = object()

    def put(message) -> bool:
        while not stop.is_set():
            try:
                channel.put(message, timeout=0.05)
                return True
            except queue.Full:
                continue
        return False

    def pump() -> None:
        try:
            for item in items:
                if not put(("item", item)):
                    return
        except BaseException as exc:  # handed to the consumer, which re-raises it
            put(("error", exc))
            return
        finally:
            close = getattr(items, "close", None)
            if close is not None:
                close()  # releases the camera
        put(("done", done))

    thread = threading.Thread(target=pump, name="aplan-vision", daemon=True)
    thread.start()

    def consume() -> Iterator:
        try:
            while True:
                kind, item = channel.get()
                if kind == "item":
                    yield item
                elif kind == "error":
                    raise item
                else:
                    return
        finally:
            stop.set()

    return consume()
