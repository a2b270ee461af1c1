"""Vision benchmark: ArUco marker detection on 1920x1080 frames of the parts tray, on one core.

Run: ``.venv/bin/python bench/bench_vision.py [--frames 300]`` (about 1 minute).

Frames are rendered by planner.runtime.tray (the pen's tray, markers 96 px wide, and a 48-item tray, markers 64 px)
before timing, with the camera degradations of the tests; each frame's truth (the uncovered markers) is known,
so the benchmark also counts frames whose detection is not exactly right. ``cv2.setNumThreads(1)`` keeps
OpenCV on one core. Rows: detection alone with APLAN's detector (one adaptive-threshold window, 23 px), the same
looking at the tray's scene box only (``aplan session --demo``: ``MarkerDetector.within``, ``tray.scene_box``; it
must find exactly the markers of the whole frame), with OpenCV's default parameters, and the whole per-frame
pipeline of ``VisionSource`` (detect, debounce, build).
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from planner import Part, Product, Tool, resolve_product  # noqa: E402
from planner.runtime.tray import BENCH, CameraModel, render_tray, scene_box, tray_layout  # noqa: E402
from planner.runtime.vision import MarkerDetector, VisionSource, marker_map  # noqa: E402


CAMERA = CameraModel(blur=1.2, noise=6, perspective=0.04, seed=1)


def frames_for(markers, marker_px: int, count: int, seed: int = 0):
    """``count`` frames with random items in the tray; blur, noise and perspective as a real camera. Returns
    the frames, their truths and the layout."""
    layout = tray_layout(markers, (1920, 1080), marker_px)
    rng = np.random.default_rng(seed)
    names = list(layout.slots)
    frames, truths = [], []
    for k in range(count):
        in_tray = {n for n in names if rng.random() < 0.5}
        frames.append(render_tray(layout, in_tray, CAMERA.blur, CAMERA.noise, CAMERA.perspective, seed=k,
                                  camera_seed=CAMERA.seed))
        truths.append({m for m, n in markers.items.items() if n not in in_tray})
    return frames, truths, layout


def big_tray():
    parts = tuple(Part(f"p{k:02d}") for k in range(47))
    return Product(parts, tuple((f"p{k:02d}", f"p{k + 1:02d}") for k in range(46)), tools=(Tool("hammer"),),
                   name="47 parts and a tool")


def timed(detect, frames, truths) -> tuple[float, float, float, int]:
    """Frames per second (1 / median time), median and 95th-percentile ms per frame, wrong frames."""
    detect(frames[0])  # warm-up
    times, wrong = [], 0
    for frame, truth in zip(frames, truths):
        start = time.perf_counter()
        seen = detect(frame)
        times.append(time.perf_counter() - start)
        wrong += seen != truth
    median = statistics.median(times)
    return 1 / median, median * 1000, float(np.percentile(times, 95)) * 1000, wrong


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--frames", type=int, default=300)
    args = parser.parse_args()
    cv2.setNumThreads(1)
    print(f"OpenCV {cv2.__version__}, {cv2.getNumThreads()} thread; {args.frames} frames of 1920x1080 per row\n")
    print("| tray | detector | frames per second (1 / median) | median ms | p95 ms | frames not exactly right |")
    print("|---|---|---:|---:|---:|---:|")
    for label, product, px in (("pen, 7 markers of 96 px", resolve_product("pen"), 96),
                               ("48 markers of 64 px", big_tray(), 64)):
        markers = marker_map(product)
        frames, truths, layout = frames_for(markers, px, args.frames)
        ours = MarkerDetector(markers.dictionary)
        within = ours.within(scene_box(layout, CAMERA), BENCH)
        opencv = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, markers.dictionary)),
                                         cv2.aruco.DetectorParameters())

        def opencv_default(frame):
            _, ids, _ = opencv.detectMarkers(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY))
            return set() if ids is None else {int(i) for i in ids.ravel()}

        source = VisionSource((), markers, ours, detections=())

        def pipeline(frame):
            seen = ours.detect(frame)
            for marker, visible in source.tracker.update(seen & markers.items.keys()):
                source.builder.change(marker, visible)
            return seen

        for name, detect in (("APLAN (window 23)", ours.detect), ("APLAN within the scene box", within.detect),
                             ("OpenCV defaults (windows 3, 13, 23)", opencv_default),
                             ("APLAN, whole VisionSource step", pipeline)):
            fps, median, p95, wrong = timed(detect, frames, truths)
            print(f"| {label} | {name} | {fps:.1f} | {median:.1f} | {p95:.1f} | {wrong} |")


if __name__ == "__main__":
    main()
