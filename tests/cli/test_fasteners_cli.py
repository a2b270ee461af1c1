"""aplan fasteners, --fasteners {tagged,auto,none}, and fasteners through a session and its replay."""
from __future__ import annotations

import json

import pytest
from real_models import BACKGROUND, real_bundles  # noqa: F401  (the exports, done in the background; a fixture)

from planner import load_product, product_to_dict, save_product
from planner.cli import main
from planner.product.synthetic import chain_product


def run(capsys, *args):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def _screwed(tmp_path, tagged: bool = True):
    """A chain p1-p2-p3; screw_1 and screw_2 join p1 and p2 (tagged as a group needing a screwdriver, or not);
    bolt_1 joins p2 and p3 (never tagged)."""
    doc = product_to_dict(chain_product(3))
    doc["parts"] += [{"id": "screw_1"}, {"id": "screw_2"}, {"id": "bolt_1"}]
    doc["contacts"] += [[p, s] for s in ("screw_1", "screw_2") for p in ("p1", "p2")]
    doc["contacts"] += [["p2", "bolt_1"], ["p3", "bolt_1"]]
    doc["tools"] = [{"id": "screwdriver"}]
    if tagged:
        doc["fasteners"] = [{"id": "screws", "parts": ["screw_1", "screw_2"], "tool": "screwdriver"}]
    path = tmp_path / "screwed.json"
    path.write_text(json.dumps(doc))
    return path


def test_fasteners_lists_and_accepts(capsys, tmp_path):
    path = _screwed(tmp_path)
    code, out, _ = run(capsys, "fasteners", path)
    assert code == 0
    assert "designer's fastener groups: 1 (2 parts)" in out and "screws: screw_1, screw_2" in out
    assert "joins p1, p2; tool screwdriver" in out
    assert "proposed fastener groups: 1 (1 parts)" in out and "why: bolt_1: name ('bolt')" in out
    code, out, _ = run(capsys, "fasteners", path, "--json")
    data = json.loads(out)
    assert [g["parts"] for g in data["designer"]] == [["screw_1", "screw_2"]]
    assert data["proposed"] == [{"id": "fasteners_p2+p3", "parts": ["bolt_1"], "hosts": ["p2", "p3"], "tool": None,
                                 "source": "proposed", "reason": "bolt_1: name ('bolt')"}]
    out_path = tmp_path / "accepted.json"
    code, out, _ = run(capsys, "fasteners", path, "-o", out_path)
    assert code == 0 and "2 fastener groups (1 proposals accepted)" in out
    accepted = load_product(out_path)
    assert [g.id for g in accepted.fasteners] == ["screws", "fasteners_p2+p3"]
    assert accepted.fasteners[1].source == "proposed" and accepted.fasteners[1].hosts == {"p2", "p3"}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["accepted.json", "screwed.json"]  # written atomically


@pytest.mark.parametrize("mode, parts, folded", [
    ("tagged", 4, "2 parts in 1 groups"), ("auto", 3, "3 parts in 2 groups"), ("none", 6, None)])
def test_stats_fastener_modes(capsys, tmp_path, mode, parts, folded):
    path = _screwed(tmp_path)
    code, out, _ = run(capsys, "stats", path, "--fasteners", mode)
    assert code == 0
    assert out.splitlines()[1].split() == ["parts", str(parts)]
    if folded:
        assert f"fasteners folded: {folded}" in out
    else:
        assert "fasteners folded" not in out
    code, out, _ = run(capsys, "stats", path, "--fasteners", mode, "--json")
    data = json.loads(out)
    assert data["parts"] == parts
    if mode == "auto":  # the chain of three: the closed forms, whatever the fasteners
        assert (data["subassemblies"], data["operations"], data["states"], data["sequences"]) == (6, 4, 4, 2)
        assert data["fasteners"]["parts"] == 3
        assert data["fasteners"]["groups"]["screws"] == {"parts": ["screw_1", "screw_2"], "hosts": ["p1", "p2"],
                                                         "tool": "screwdriver", "install_operations": 2}
        assert data["fasteners"]["groups"]["fasteners_p2+p3"]["install_operations"] == 2
    if mode == "none":
        assert "fasteners" not in data


def test_stats_prints_the_install_operations(capsys, tmp_path):
    code, out, _ = run(capsys, "stats", _screwed(tmp_path), "--fasteners", "auto")
    assert "    screws: 2 parts joining p1, p2, tool screwdriver; installed by 2 operations" in out
    assert "    fasteners_p2+p3: 1 part joining p2, p3; installed by 2 operations" in out


def test_intentions_and_pomdp_fold_the_fasteners(capsys, tmp_path):
    path = _screwed(tmp_path)
    code, out, _ = run(capsys, "intentions", path, "--full", "--fasteners", "auto")
    assert code == 0 and len(out.splitlines()) == 2  # the chain of three has 2 full sequences
    model = tmp_path / "m.pomdp"
    code, out, _ = run(capsys, "pomdp", path, "-o", model)
    assert code == 0
    observations = next(line for line in model.read_text().splitlines() if line.startswith("observations:"))
    # tagged: the screws are folded (seen with their operation), the bolt is a part
    assert "o8_p1_p2_screw_1_screw_2_screwdriver" in observations.split() and "o1_bolt_1" in observations.split()


def test_a_fastener_that_joins_one_part_is_refused(capsys, tmp_path):
    doc = json.loads(_screwed(tmp_path).read_text())
    doc["fasteners"] = [{"id": "loose", "parts": ["bolt_1"], "hosts": ["p3"]}]
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc))
    for command in ("stats", "fasteners"):
        code, out, err = run(capsys, command, path)
        assert code == 1 and out == "" and "Traceback" not in err
        assert "fasteners[0]: fastener group 'loose' (bolt_1) joins only 'p3'" in err


def test_pen_stats_unchanged(capsys):
    _, tagged, _ = run(capsys, "stats", "pen")
    _, auto, _ = run(capsys, "stats", "pen", "--fasteners", "auto")
    assert tagged == auto and "fasteners folded" not in tagged


def test_a_session_picks_the_fasteners_and_replays(capsys, tmp_path):
    path = _screwed(tmp_path)
    log = tmp_path / "s.jsonl"
    # full sequence 1 (aplan intentions --full): the operator screws p1 to p2 first, the robot adds p3
    code, out, err = run(capsys, "session", path, "--demo", 1, "--log", log, "--fasteners", "auto")
    assert code == 0, err
    assert "seen p1+p2+screw_1+screw_2+[screwdriver]" in out + err
    start = json.loads(log.read_text().splitlines()[0])
    # the product before folding, with the accepted proposal: the replay folds the same groups
    assert [g["id"] for g in start["product"]["fasteners"]] == ["screws", "fasteners_p2+p3"]
    instructions = [json.loads(line).get("instruction", "") for line in log.read_text().splitlines()]
    assert "join {p1, p2} with {p3} fastened by bolt_1" in instructions  # the robot installs the bolt
    code, out, err = run(capsys, "replay", log)
    assert code == 0 and "beliefs reproduced at all" in out


def test_save_keeps_older_files_unchanged(tmp_path):
    save_product(chain_product(3), tmp_path / "c.json")
    assert "fasteners" not in json.loads((tmp_path / "c.json").read_text())


def test_accepted_product_elsewhere_keeps_its_meshes(capsys, tmp_path):
    doc = json.loads(_screwed(tmp_path).read_text())
    doc["parts"][0]["mesh"] = "meshes/p1.stl"
    source = tmp_path / "bundle" / "product.json"
    source.parent.mkdir()
    source.write_text(json.dumps(doc))
    out = tmp_path / "elsewhere" / "accepted.json"
    out.parent.mkdir()
    code, _, _ = run(capsys, "fasteners", source, "-o", out)
    assert code == 0 and load_product(out).parts[0].mesh == "../bundle/meshes/p1.stl"
    code, _, err = run(capsys, "fasteners", source, "-o", source)  # an existing output needs --force
    assert code == 1 and "--force" in err
    code, _, _ = run(capsys, "fasteners", source, "-o", source, "--force")  # in place: the paths stay
    assert code == 0 and load_product(source).parts[0].mesh == "meshes/p1.stl"
    assert [g.id for g in load_product(source).fasteners] == ["screws", "fasteners_p2+p3"]


@pytest.mark.freecad
def test_the_truck_with_its_screws_folded(capsys, real_bundles):  # noqa: F811
    code, out, _ = run(capsys, "stats", real_bundles["toy_truck"], "--fasteners", "auto", "--subassemblies", "designer")
    # 61 parts, 38 screws folded in 22 groups (wood_screw_004 joins one part only); the 23 parts left are still
    # past the AND/OR limit in one level
    assert out.splitlines()[1].split() == ["parts", "23"]
    assert "fasteners folded: 38 parts in 22 groups" in out
    assert "fasteners_cabin_door_001+cabin_hood_001: 2 parts joining cabin_door_001, cabin_hood_001" in out
    assert code == 3 and "at least 1,000,001 connected part sets" in out
