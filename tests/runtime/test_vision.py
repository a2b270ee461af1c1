"""Marker vision on frames the tests render: detection, debounce, observations of a full pen assembly under
blur, noise, perspective and occlusion, the sources' errors, and the printable marker sheet."""
from __future__ import annotations

import logging

import cv2
import numpy as np
import pytest
from figure_support import pyplot_untouched

from planner import BLANK, Observation, make_plan, product_from_dict, product_to_dict
from planner.decision import intention_model
from planner.runtime.interfaces import Instruction
from planner.runtime.scripted import ScriptedOperator
from planner.runtime.sheet import write_marker_sheet
from planner.runtime.tray import BENCH, CameraModel, SimulatedCell, render_tray, scene_box, tray_layout
from planner.runtime.vision import (
    MarkerDetector,
    MarkerTracker,
    ObservationBuilder,
    VisionError,
    VisionSource,
    default_markers,
    image_frames,
    marker_map,
    video_frames,
)

SMALL = ((960, 540), 48)  # frame size and marker pixels: fast, markers as small as a 1080p camera 2 m away sees


@pytest.fixture(scope="module")
def plan(pen):
    return make_plan(pen)


@pytest.fixture(scope="module")
def model(plan):
    return intention_model(plan)


@pytest.fixture(scope="module")
def markers(pen):
    return marker_map(pen)


def test_pen_markers(pen, markers):
    assert markers.dictionary == "DICT_4X4_50"
    assert markers.items == {0: "ink", 1: "cartridge", 2: "head", 3: "body", 4: "cap", 5: "button", 6: "hammer"}
    assert markers.tools == {"hammer"}


def test_default_markers_and_missing_ones(pen):
    doc = product_to_dict(pen)
    del doc["markers"]
    bare = product_from_dict(doc)
    assert default_markers(bare).ids == (("ink", 0), ("cartridge", 1), ("head", 2), ("body", 3), ("cap", 4),
                                         ("button", 5), ("hammer", 6))
    assert marker_map(bare).items == marker_map(pen).items
    doc["markers"] = {"ids": {"ink": 0, "cartridge": 1}}
    with pytest.raises(VisionError, match="no marker for head, body, cap, button, hammer; add them"):
        marker_map(product_from_dict(doc))


def test_default_markers_of_a_product_with_more_than_fifty_items():
    # 82 parts (an assembly with a bolt circle of 40 bolts and 40 nuts): DICT_4X4_50 cannot hold them; the
    # next of its family can, and every part is seen by the detector's dictionary.
    from planner.product.synthetic import chain_product

    for count, dictionary in ((50, "DICT_4X4_50"), (51, "DICT_4X4_100"), (82, "DICT_4X4_100"), (251, "DICT_4X4_1000")):
        product = chain_product(count)
        assert product.markers is None
        markers = default_markers(product)
        assert markers.dictionary == dictionary and len(markers.ids) == count
        assert sorted(marker_map(product).items) == list(range(count))


@pytest.mark.parametrize("camera", [CameraModel(), CameraModel(blur=1.5), CameraModel(noise=10),
                                    CameraModel(perspective=0.06, seed=2)],
                         ids=["clean", "blur", "noise", "perspective"])
def test_detector_sees_exactly_the_uncovered_markers(markers, camera):
    layout = tray_layout(markers, *SMALL)
    detector = MarkerDetector()
    for in_tray in ({"ink", "cap", "hammer"}, set(), set(markers.items.values())):
        frame = render_tray(layout, in_tray, camera.blur, camera.noise, camera.perspective, camera_seed=camera.seed)
        expected = {k for k, name in markers.items.items() if name not in in_tray}
        assert detector.detect(frame) == expected


@pytest.mark.parametrize("pixels", [40, 200])
def test_marker_sizes_the_default_detector_covers(markers, pixels):
    layout = tray_layout(markers, (1920, 1080), pixels)
    frame = render_tray(layout, {"ink"}, blur=1.2, noise=6, perspective=0.04, seed=pixels, camera_seed=pixels)
    assert MarkerDetector().detect(frame) == {1, 2, 3, 4, 5, 6}


def test_unknown_dictionary():
    with pytest.raises(VisionError, match="unknown marker dictionary 'DICT_9X9_1'"):
        MarkerDetector("DICT_9X9_1")
    with pytest.raises(VisionError, match="evenly spaced"):
        MarkerDetector(threshold_windows=(3, 13, 33))


def test_tracker_ignores_flickers_shorter_than_the_debounce():
    tracker = MarkerTracker([0, 1], debounce=3)
    seen = [{0}, {0}, set(), {0}, {0, 1}, {0, 1}, {0}, {0}, {0}]
    changes = [tracker.update(s) for s in seen]
    assert changes == [[], [], [], [], [], [(0, True)], [], [], []]
    assert tracker.visible == {0: True, 1: False}


def test_builder_rules(markers):
    builder = ObservationBuilder(markers)
    ink, cartridge, head, hammer = 0, 1, 2, 6
    assert builder.change(ink, True) is None
    assert builder.change(ink, False) is None  # put back before the operation closed
    assert builder.change(cartridge, True) is None
    assert builder.change(head, True) is None
    assert builder.change(hammer, True) == Observation(("cartridge", "head"), "hammer")
    assert builder.change(hammer, False) is None  # the hammer back in the tray
    assert builder.change(head, False) is None and builder.change(head, True) is None  # occluded, seen again
    builder.expect_robot(["ink"], "hammer")  # the robot takes the ink and uses the hammer
    assert builder.change(ink, True) is None and builder.change(hammer, True) is None
    assert builder.change(hammer, False) is None
    assert builder.quiet() == BLANK
    assert builder.change(hammer, True) == Observation((), "hammer")  # joins two subassemblies


def test_builder_closes_toolless_operations_at_quiet_periods(markers):
    builder = ObservationBuilder(markers, close_without_tool=True)
    builder.change(3, True)
    builder.change(5, True)
    assert builder.quiet() == Observation(("body", "button"), None)
    assert builder.quiet() == BLANK


def _recover(plan, model, markers, sequence, camera, size=SMALL, debounce=3):
    operator = ScriptedOperator.following(model, sequence)
    cell = SimulatedCell(tray_layout(markers, *size), operator, camera)
    source = VisionSource(cell, markers, debounce=debounce, quiet_frames=20)
    seen = [source.observe() for _ in range(len(plan.product.parts) - 1)]
    return seen, cell, source


CAMERAS = {"clean": CameraModel(), "blur": CameraModel(blur=1.6, seed=1), "noise": CameraModel(noise=12, seed=2),
           "perspective": CameraModel(perspective=0.06, seed=3), "occlusion": CameraModel(hands=True, seed=4),
           "all": CameraModel(blur=1.3, noise=8, perspective=0.05, hands=True, seed=5)}


@pytest.mark.parametrize("name", list(CAMERAS))
def test_full_pen_assembly_is_recovered_exactly(plan, model, markers, name):
    sequences = model.full_sequences()
    sequence = int(sequences[list(CAMERAS).index(name) * 5 % len(sequences)])
    seen, cell, source = _recover(plan, model, markers, sequence, CAMERAS[name])
    truth = [plan.observations[plan.operation_observation[op]] for op in cell.operator.done]
    assert len(truth) == 5 and truth == cell.operator_observations
    assert seen == truth
    assert source.observe() == BLANK  # the operator has finished: nothing happens for the quiet period


def test_detection_at_1080p(markers):
    camera = CAMERAS["all"]
    layout = tray_layout(markers, (1920, 1080), 96)
    detector = MarkerDetector()
    for in_tray in ({"ink", "cap", "hammer"}, {"body"}):
        frame = render_tray(layout, in_tray, camera.blur, camera.noise, camera.perspective, camera_seed=camera.seed)
        assert detector.detect(frame) == {k for k, name in markers.items.items() if name not in in_tray}


@pytest.mark.parametrize("size, camera", [((1920, 1080), CameraModel(1.2, 6, 0.04, hands=True, seed=0)),
                                          ((1280, 720), CameraModel(0.8, 10, 0.07, hands=True, seed=3))],
                         ids=["demo", "tilted"])
def test_detection_within_the_scene_box_is_that_of_the_whole_frame(plan, model, markers, size, camera):
    """Frames of the simulated cell (hands and arms over the tray, a corner of every slot covered): outside
    scene_box they show the bench top alone (and the grain), and a detector looking at the box only finds the
    markers of the whole frame at the same corners; the whole frame holds no candidate square beyond a threshold
    window from the box."""
    import dataclasses
    import itertools

    layout = tray_layout(markers, size, margin=camera.perspective + 0.02)
    x0, y0, x1, y1 = box = scene_box(layout, camera)
    outside = np.ones(layout.size[::-1], bool)
    outside[y0:y1, x0:x1] = False
    sequence = int(model.full_sequences()[camera.seed])
    cells = [SimulatedCell(layout, ScriptedOperator.following(model, sequence), c, hold=5)
             for c in (camera, dataclasses.replace(camera, noise=0))]
    whole = MarkerDetector(markers.dictionary)
    within = whole.within(box, BENCH)
    for frame, bare in itertools.islice(zip(*cells), 10):
        assert (bare[outside] == BENCH).all()
        corners, ids, rejected = whole._detector.detectMarkers(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY))
        found = within.found(frame)
        assert [i for i, _ in found] == ([] if ids is None else ids.ravel().tolist())
        assert all(np.array_equal(c.reshape(4, 2), f) for c, (_, f) in zip(corners, found))
        points = np.concatenate([c.reshape(-1, 2) for c in (*corners, *rejected)])  # the tray's edge among them
        reach = whole.threshold_windows[-1] // 2 + 1  # a pixel's threshold reads the box from there
        assert ((points >= (x0 - reach, y0 - reach)) & (points < (x1 + reach, y1 + reach))).all()
    first = cells[0].operator_observations[0]  # 10 frames: two reaches into the tray (5 frames each), hands over both
    assert len(first.parts) + (first.tool is not None) >= 2


def test_without_debounce_flickers_become_operations(plan, model, markers):
    """The occlusion camera makes the hammer's marker flicker while in use: debounce is what removes it."""
    seen, cell, _ = _recover(plan, model, markers, int(model.full_sequences()[0]), CAMERAS["occlusion"], debounce=1)
    assert seen != cell.operator_observations and Observation((), "hammer") in seen


def test_robot_picks_are_not_the_operators(plan, model, markers):
    sequence = int(model.full_sequences()[0])
    operator = ScriptedOperator.following(model, sequence)
    cell = SimulatedCell(tray_layout(markers, *SMALL), operator)
    source = VisionSource(cell, markers, quiet_frames=20)
    first = source.observe()
    robot_op = operator.remaining[0]
    first_side, second_side = (tuple(sorted(s)) for s in plan.andor.inputs(robot_op))
    instruction = Instruction(1, 0, "robot", robot_op, (first_side, second_side), plan.tags.tool[robot_op])
    source.robot_acting(instruction)
    cell.robot(instruction)
    rest = [source.observe() for _ in range(3)]
    truth = cell.operator_observations
    assert [first] + rest == truth and len(truth) == 4  # the robot's operation is not among the operator's


def test_robot_expectations_last_one_step(markers):
    said = []
    # frames: the robot takes the ink (marker 0); the cartridge (1) and the hammer (6) never show for it
    source = VisionSource([], markers, on_warning=said.append, quiet_frames=5,
                          detections=[{0}] * 8 + [{0, 1}] * 3 + [{0, 1, 6}] * 3 + [{0, 1}] * 8)
    join = Instruction(1, 0, "a", 7, (("ink",), ("cartridge",)), "hammer")
    source.robot_acting(join)
    source.builder.robot_parts.add("cartridge")  # as if the robot had been sent for it too
    assert source.observe() == BLANK  # the ink is the robot's
    source.robot_acting(Instruction(2, 1, "wait"))
    assert "never showed cartridge, hammer leaving the tray" in said[0]
    assert source.observe() == Observation(("cartridge",), "hammer")  # the operator's, no longer swallowed
    own = VisionSource([], markers, quiet_frames=5, robot_uses_tray_tools=False,
                       detections=[{0}] * 4 + [{0, 6}] * 4)
    own.robot_acting(join)
    assert own.observe() == Observation((), "hammer")  # a robot with its own hammer: the tray's is the operator's


def test_unknown_marker_ids_warn_once(markers, caplog):
    source = VisionSource([], markers, detections=[{42}, {42, 0}, {42, 0}, {42, 0}] + [set(), {0}] * 30,
                          quiet_frames=10)
    with caplog.at_level(logging.WARNING, logger="planner.runtime.vision"):
        assert source.observe() == BLANK
    caught = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert caught == ["marker 42 is not in the product's marker map (DICT_4X4_50); ignored"]
    assert source.builder.pending == ["ink"]


def test_end_of_frames(markers):
    source = VisionSource([], markers, detections=[set()] * 3, quiet_frames=10)
    assert source.observe() == BLANK  # frames were read in this call
    assert source.observe() is None


def test_video_file_source(plan, model, markers, tmp_path):
    operator = ScriptedOperator.following(model, int(model.full_sequences()[3]))
    cell = SimulatedCell(tray_layout(markers, *SMALL), operator)
    frames = [next(cell) for _ in range(110)]
    path = tmp_path / "tray.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 30, SMALL[0])
    assert writer.isOpened()
    for frame in frames:
        writer.write(frame)
    writer.release()
    source = VisionSource(video_frames(path), markers, quiet_frames=20)
    seen = []
    while (observation := source.observe()) is not None:
        if observation != BLANK:
            seen.append(observation)
    assert seen == cell.operator_observations[:len(seen)] and len(seen) >= 4


def test_image_folder_source(markers, tmp_path):
    layout = tray_layout(markers, *SMALL)
    in_tray = set(markers.items.values())
    for k, taken in enumerate(["ink", "cartridge", "hammer", None]):
        in_tray.discard(taken)
        for j in range(3):
            cv2.imwrite(str(tmp_path / f"{k:03d}_{j}.png"), render_tray(layout, in_tray))
    (tmp_path / "notes.txt").write_text("not an image, skipped by its suffix")
    source = VisionSource(image_frames(tmp_path), markers, quiet_frames=5)
    assert source.observe() == Observation(("cartridge", "ink"), "hammer")


def test_sources_fail_clearly(tmp_path):
    with pytest.raises(VisionError, match="no such video file"):
        video_frames(tmp_path / "missing.mp4")
    (tmp_path / "junk.mp4").write_bytes(b"\x00not a video" * 100)
    with pytest.raises(VisionError, match="junk.mp4"):
        list(video_frames(tmp_path / "junk.mp4"))
    with pytest.raises(VisionError, match="no such folder of images"):
        image_frames(tmp_path / "nowhere")
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(VisionError, match="holds no images"):
        image_frames(empty)
    (empty / "001.png").write_bytes(b"\x89PNG\r\n\x1a\n broken")
    with pytest.raises(VisionError, match=r"001\.png: cannot be read as an image"):
        list(image_frames(empty))


def test_camera_that_cannot_be_opened():
    from planner.runtime.vision import camera_frames

    with pytest.raises(VisionError, match="camera 97 cannot be opened; check the index"):
        camera_frames(97)


def test_marker_sheet_is_detectable(pen, markers, tmp_path, monkeypatch):
    png = tmp_path / "sheet.png"
    with pyplot_untouched(monkeypatch):
        assert write_marker_sheet(pen, png) == 7
    sheet = cv2.imread(str(png))
    assert abs(sheet.shape[0] / sheet.shape[1] - 297 / 210) < 0.01  # A4
    assert MarkerDetector().detect(sheet) == set(markers.items)
    pdf = tmp_path / "sheet.pdf"
    write_marker_sheet(pen, pdf)
    assert pdf.read_bytes()[:5] == b"%PDF-"
    with pytest.raises(Exception, match=r"\.pdf or \.png"):
        write_marker_sheet(pen, tmp_path / "sheet.svg")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sheet.pdf", "sheet.png"]


def test_marker_sheet_pages(tmp_path, monkeypatch):
    import re

    from planner import Part, Product

    parts = tuple(Part(f"p{k}") for k in range(30))
    product = Product(parts, tuple((f"p{k}", f"p{k + 1}") for k in range(29)))
    with pyplot_untouched(monkeypatch):
        assert write_marker_sheet(product, tmp_path / "big.pdf") == 30
    pages = re.findall(rb"/Type\s*/Page\b(?!s)", (tmp_path / "big.pdf").read_bytes())
    assert len(pages) == 3  # 12 markers of 40 mm per A4 page (3 columns, 4 rows)


def test_background_reading_keeps_order_and_reraises():
    from planner.runtime.vision import in_background

    def items():
        yield from range(5)
        raise VisionError("camera 0 stopped")

    stream = in_background(items())
    assert [next(stream) for _ in range(5)] == list(range(5))
    with pytest.raises(VisionError, match="camera 0 stopped"):
        next(stream)
    endless = in_background(iter(int, 1), maxsize=4)  # an endless source, stopped by closing
    assert next(endless) == 0
    endless.close()
    import threading
    import time

    deadline = time.monotonic() + 2
    while any(t.name == "aplan-vision" for t in threading.enumerate()) and time.monotonic() < deadline:
        time.sleep(0.01)
    assert not any(t.name == "aplan-vision" for t in threading.enumerate())


def test_a_tray_layout_keeps_its_margin_and_every_marker_is_seen():
    """35 markers of 96 px fill 1,055 of 1,080 rows: the top row is 69 px from the edge, which a camera tilted by
    4 % (43 px) nearly reaches, and markers there flicker (the pump's top level). With the demo's margin (the
    tilt and 2 % more) the markers shrink to fit (86 px) and every one is seen in every frame; a small tray
    keeps its 96 px."""
    from planner.product import Part, Product

    many = marker_map(Product(tuple(Part(f"p{k}") for k in range(35)), ()))
    layout = tray_layout(many, (1920, 1080), 96, margin=0.06)
    assert layout.marker_px == 86 and tray_layout(many).marker_px == 96
    assert all(0.06 * 1080 <= y and y + 86 <= 0.94 * 1080 for _, y in layout.slots.values())
    assert tray_layout(marker_map(Product(tuple(Part(f"p{k}") for k in range(12)), ())), margin=0.06).marker_px == 96
    detector = MarkerDetector()
    for seed in range(6):
        frame = render_tray(layout, set(), 1.2, 6, 0.04, seed=seed, camera_seed=0)
        assert detector.detect(frame) == set(many.items), seed


def test_noise_is_added_with_saturation(markers):
    """The frame is the noiseless scene plus a window of the camera's grain, clipped to 0..255 on every channel:
    the grain is drawn once from the camera's seed (OpenCV's randn), 64 pixels taller and wider than the frame,
    and each frame's seed draws the window's corner."""
    layout = tray_layout(markers, *SMALL)
    clean = render_tray(layout, {"ink"}, blur=1.0)
    noisy = render_tray(layout, {"ink"}, blur=1.0, noise=40, seed=7, camera_seed=3)
    cv2.setRNGSeed(3)
    height, width = clean.shape[:2]
    grain = np.empty((height + 64, width + 64), np.int16)
    cv2.randn(grain, 0, 40)
    row, column = np.random.default_rng(7).integers(0, 65, 2)
    window = grain[row:row + height, column:column + width]
    assert np.array_equal(noisy, np.clip(clean.astype(np.int16) + window[:, :, None], 0, 255).astype(np.uint8))
    assert noisy.min() == 0 and noisy.max() == 255   # saturated both ways
    assert np.array_equal(render_tray(layout, {"ink"}, blur=1.0, noise=40, seed=7, camera_seed=3), noisy)
    frames = [render_tray(layout, {"ink"}, blur=1.0, noise=6, seed=k, camera_seed=3).astype(int) - clean
              for k in range(8)]
    assert all(abs(f.std() - 6) < 0.3 for f in frames)     # the grain's deviation, on every frame
    assert all(abs(np.corrcoef(a.ravel(), b.ravel())[0, 1]) < 0.05 for a, b in zip(frames, frames[1:]))


@pytest.mark.parametrize("blur, perspective", [(1.2, 0.04), (0.0, 0.04), (1.5, 0.0)])
def test_an_occluded_frame_equals_its_scene_drawn_again_whole(markers, blur, perspective):
    """Occluders are tilted and blurred again only where they can reach: the frame equals the tray drawn with
    them, tilted and blurred whole (hands at the frame's edges and beyond included)."""
    from planner.runtime.tray import Occluder, _blurred, _drawn, _tilt

    layout = tray_layout(markers, margin=0.06)
    rng = np.random.default_rng(4)
    width, height = layout.size
    for trial in range(6):
        in_tray = {name for name in layout.slots if rng.random() < 0.5}
        occluders = tuple(Occluder((int(rng.integers(-50, width + 50)), int(rng.integers(-50, height + 50))),
                                   (int(rng.integers(1, 300)), int(rng.integers(1, 60))), float(rng.uniform(0, 360)))
                          for _ in range(int(rng.integers(1, 5))))
        frame = render_tray(layout, in_tray, blur, 0, perspective, occluders, camera_seed=trial)
        whole = _drawn(layout, frozenset(in_tray)).copy()
        for o in occluders:
            cv2.ellipse(whole, o.center, o.axes, o.angle, 0, 360, (120, 150, 200), -1)
        whole = _blurred(_tilt(layout, perspective, trial, whole), blur)
        assert np.array_equal(frame, whole), trial
        assert not np.array_equal(frame, render_tray(layout, in_tray, blur, 0, perspective, camera_seed=trial))