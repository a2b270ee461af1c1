"""Rendering benchmark: the CPU time of one frame of the demo camera (``aplan session --demo``), on one core.

Run: ``.venv/bin/python bench/bench_render.py [--frames 200]`` (a few seconds).

The frames are the pen's tray (1920x1080, markers 96 px) with the demo's camera: Gaussian blur 1.2 px, noise of
6 grey levels, a 4 % tilt; a frame with hands is one with two occluders (a hand over a slot, an arm across the
tray), a frame of the scene is one without. CPU time (``time.process_time``), so that a machine loaded by other
work changes the figures less than wall time would.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import cv2  # noqa: E402

from planner import resolve_product  # noqa: E402
from planner.runtime.tray import Occluder, render_tray, tray_layout  # noqa: E402
from planner.runtime.vision import marker_map  # noqa: E402


def cpu_ms(render, frames: int) -> float:
    """CPU milliseconds per call of ``render(k)``, k = 0 .. frames - 1, after one call to warm up."""
    render(0)
    start = time.process_time()
    for k in range(frames):
        render(k)
    return (time.process_time() - start) / frames * 1000


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--frames", type=int, default=200)
    args = parser.parse_args()
    cv2.setNumThreads(1)
    layout = tray_layout(marker_map(resolve_product("pen")), margin=0.06)
    items = set(layout.slots)
    x, y = layout.slots["ink"]
    px = layout.marker_px
    hands = (Occluder((x + px // 2, y + px // 2), (px // 2, px // 3), 30.0),
             Occluder((layout.size[0] // 2, layout.size[1] // 2), (px * 3, px // 4), 10.0))
    scene = cpu_ms(lambda k: render_tray(layout, items, 1.2, 6, 0.04, seed=k, camera_seed=0), args.frames)
    handed = cpu_ms(lambda k: render_tray(layout, items, 1.2, 6, 0.04, hands, seed=k, camera_seed=0), args.frames)
    print(f"OpenCV {cv2.__version__}, 1 thread; {args.frames} frames of 1920x1080 per row\n")
    print("| frame | CPU ms per frame |\n|---|---:|")
    print(f"| the scene (no hands) | {scene:.1f} |\n| with hands (two occluders) | {handed:.1f} |")


if __name__ == "__main__":
    main()
