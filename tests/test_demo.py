"""``bash scripts/demo.sh``'s steps (``scripts/demo.py``, without the set-up): the pen's plan, a policy bounded by
trials, a simulated camera session in which the robot decides, and the belief figure, checked on what a
newcomer reads (the printed lines) and sees (the figure's pixels)."""
from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest
from pictures import assert_belief_plot, read_picture

REPO = Path(__file__).resolve().parent.parent


def _demo_module():
    spec = importlib.util.spec_from_file_location("aplan_demo", REPO / "scripts" / "demo.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """The demo run once into a folder that holds a previous run's stale file (replaced, not merged)."""
    module = _demo_module()
    out = tmp_path_factory.mktemp("demo") / "demo"
    out.mkdir()
    (out / "stale.txt").write_text("from an earlier run")
    return module, out, module.run_demo(out)


def test_demo_prints_what_happened(demo):
    module, out, lines = demo
    text = "\n".join(lines)
    # the paper's pen (Sec. VI): 69 intentions, 12 observations; 24 full sequences (the factored view's)
    assert "69 intentions (24 full sequences)" in lines[1]
    assert "12 observations" in lines[2] and "solved in 50 trials" in lines[2]
    events = [json.loads(line) for line in (out / "session.jsonl").read_text().splitlines()]
    steps = [e for e in events if e["event"] == "action"]
    shown = [line for line in lines if line.startswith("   step ")]
    assert len(shown) == len(steps) >= 2  # one line per decision of the robot, as logged
    for line, step in zip(shown, steps):  # what the robot did, as the log says
        assert ("robot: wait;" in line) if step["name"] == "wait" else (step["instruction"] in line)
    assert any("robot: join" in line for line in shown)  # the robot acted, not only waited
    end = next(e for e in events if e["event"] == "end")
    assert end["reason"] == "assembled" and f"ended: {end['message']}" in text
    assert f"{out.name}/belief.png" in text or str(out / "belief.png") in text
    assert len(lines) <= 16  # a few lines, whatever the session's length on the pen


def test_demo_writes_the_figure_and_only_its_outputs(demo):
    module, out, lines = demo
    assert sorted(p.name for p in out.iterdir()) == sorted(module.OUTPUTS)  # the stale file is gone
    assert not [p for p in out.parent.iterdir() if p.name.startswith(".")]  # no work folder left behind
    assert_belief_plot(out / "belief.png")
    picture = read_picture(out / "belief.png")
    # the robot's actions are marked (red triangles in the top strip): one mark per non-wait action at least
    top = picture.crop(0, 0, picture.size[0], picture.size[1] // 8)
    assert top.share(top.coloured(0.0, width=15, saturation=0.6, value=0.5)) > 0.0005


def test_demo_failure_keeps_the_previous_run(demo):
    module, out, lines = demo
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    with pytest.raises(module.StepFailed) as failed:
        module.run_demo(out, sequence=3)  # not a full assembly sequence: the session refuses it
    assert failed.value.code == 2 and "--demo 3 is not a full assembly sequence" in str(failed.value)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert not [p for p in out.parent.iterdir() if p.name.startswith(".")]
