"""The first command on a real product and the messages that misled (issue 22, items 8 and 10): a product drawn
in CAD without fastener groups or subassemblies of its own is planned with the planner's proposals by default
(one note says so, and the options that turn it off); long messages are one line, the whole of them behind
``--verbose``; ``--max-components`` is checked when parsed; a fastener a subassembly lists is named as one.
Each case runs the command line (``planner.cli.main``) and asserts the exit status, a one-line message naming
the place and the fix, no traceback, and nothing written."""
from __future__ import annotations

import json
from pathlib import Path

import pytest
from aplan_runner import run_aplan

from planner.cli.options import LONG_MESSAGE

NOTE = "has no fastener groups or subassemblies of its own"


def _product(folder: Path, name: str, parts: list[str], contacts: list[list[str]], meshes: bool = True,
             **sections) -> Path:
    """A product file of ``parts`` touching as ``contacts`` (no obstructions: every split is free); with
    ``meshes``, every part names a mesh, as a product drawn in CAD does (planning reads none)."""
    doc = {"format": "aplan-product", "version": 1, "name": name,
           "parts": [{"id": p, **({"mesh": f"meshes/{p}.stl"} if meshes else {})} for p in parts],
           "contacts": contacts, **sections}
    path = folder / f"{name}.json"
    path.write_text(json.dumps(doc))
    return path


def _one_line(done, *words: str) -> None:
    lines = [line for line in done.stderr.splitlines() if line.startswith("aplan: error:")]
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert len(lines[0]) <= LONG_MESSAGE + 120, lines[0]  # the fix fits in the line, the detail is elsewhere
    for word in words:
        assert word in lines[0], (word, lines[0])


# A screw joining a and b of the chain a - b - c: proposed by its name (it touches two parts).
SCREWED = (["a", "b", "c", "screw_1"], [["a", "b"], ["b", "c"], ["a", "screw_1"], ["b", "screw_1"]])


def test_a_cad_product_without_structure_is_planned_with_the_proposals(tmp_path):
    path = _product(tmp_path, "screwed", *SCREWED)
    done = run_aplan("stats", path, "--json")
    assert done.returncode == 0, done.stderr
    notes = [line for line in done.stderr.splitlines() if NOTE in line]
    assert len(notes) == 1 and "--fasteners tagged" in notes[0] and "1 fastener group" in notes[0]
    figures = json.loads(done.stdout)
    # Folded, the screw is installed by the operation joining a and b: the chain of 3, whose 2 sequences
    # join a-b or b-c first (closed form: a chain of n parts has 2^(n-2) sequences).
    assert figures["parts"] == 3 and figures["sequences"] == 2
    assert figures == json.loads(run_aplan("stats", path, "--json", "--fasteners", "auto").stdout)
    # The option the note names turns it off: the file as it is, four parts, and no note.
    as_filed = run_aplan("stats", path, "--json", "--fasteners", "tagged", "--subassemblies", "designer")
    assert as_filed.returncode == 0 and NOTE not in as_filed.stderr
    assert json.loads(as_filed.stdout)["parts"] == 4


def test_the_same_default_on_every_command_that_takes_a_product(tmp_path):
    path = _product(tmp_path, "screwed", *SCREWED)
    for argv in (["intentions", path, "--full"], ["sequence", path, "--rank", "0"],
                 ["simulate", path, "--random", "1", "--expansions", "2", "--json"]):
        done = run_aplan(*argv)
        assert done.returncode == 0 and NOTE in done.stderr, (argv, done.stderr)
    # The two full sequences of the folded chain (the intention graph's full sequences).
    assert len(run_aplan("intentions", path, "--full").stdout.splitlines()) == 2


def test_products_with_their_own_structure_or_no_cad_keep_it(tmp_path):
    """The designer's fastener groups, the designer's subassemblies, a product without meshes (synthetic, by
    hand) and the pen are planned as they are, without a note."""
    own = _product(tmp_path, "own", *SCREWED, fasteners=[{"id": "g", "parts": ["screw_1"], "hosts": ["a", "b"]}])
    structured = _product(tmp_path, "structured", *SCREWED, subassemblies=[{"id": "u", "parts": ["b", "c"]}])
    by_hand = _product(tmp_path, "by_hand", *SCREWED, meshes=False)
    for path, parts in ((own, 3), (by_hand, 4)):
        done = run_aplan("stats", path, "--json")
        assert done.returncode == 0 and NOTE not in done.stderr and json.loads(done.stdout)["parts"] == parts
    done = run_aplan("stats", structured, "--json")  # u and the top level; the screw stays a part
    assert done.returncode == 0 and NOTE not in done.stderr
    assert [row["level"] for row in json.loads(done.stdout)["levels"]] == ["u", "top"]
    pen = run_aplan("stats", "pen", "--json")
    figures = json.loads(pen.stdout)
    assert NOTE not in pen.stderr and (figures["intentions"], figures["states"]) == (69, 18)


@pytest.mark.parametrize("value", ["1", "0", "-3", "nan", "2.5"])
def test_max_components_is_checked_when_parsed(tmp_path, value):
    done = run_aplan("stats", "pen", "--subassemblies", "auto", "--max-components", value)
    assert done.returncode == 2 and "--max-components" in done.stderr and "Traceback" not in done.stderr
    assert "max_components" not in done.stderr


def test_a_fastener_listed_in_a_subassembly(tmp_path):
    """Folded, a fastener is no member: a subassembly keeps its other members; one left with a single member is
    dissolved (its member takes its place) with one warning naming the subassembly and the fastener (a bundle
    the export wrote always reads back, fasteners folded or not: issue 26, item 2)."""
    fastened = [{"id": "g", "parts": ["screw_1"]}]
    kept = _product(tmp_path, "kept", *SCREWED, fasteners=fastened,
                    subassemblies=[{"id": "u", "parts": ["a", "screw_1", "b"]}])
    done = run_aplan("stats", kept, "--level", "u", "--json")
    assert done.returncode == 0, done.stderr
    figures = json.loads(done.stdout)  # a and b, the screw installed by the operation joining them
    assert (figures["parts"], figures["sequences"]) == (2, 1)
    alone = _product(tmp_path, "alone", *SCREWED, fasteners=fastened,
                     subassemblies=[{"id": "u", "parts": ["a", "screw_1"]}])
    before = sorted(p.name for p in tmp_path.iterdir())
    done = run_aplan("stats", alone, "--json")
    assert done.returncode == 0, done.stderr
    assert "subassembly 'u' is dissolved: folding the fastener screw_1 leaves it only a" in done.stderr
    assert "neither a part" not in done.stderr and sorted(p.name for p in tmp_path.iterdir()) == before
    (tmp_path / "flat").mkdir()
    flat = _product(tmp_path / "flat", "alone", *SCREWED, fasteners=fastened)  # planned as if never listed
    assert json.loads(done.stdout) == json.loads(run_aplan("stats", flat, "--json").stdout)
    assert run_aplan("stats", alone, "--fasteners", "none").returncode == 0  # then the screw is a part


def _interlocked(folder: Path) -> Path:
    """Three parts in a row; b and c block each other along every axis (an overlap in the model)."""
    path = _product(folder, "stuck", ["a", "b", "c"], [["a", "b"], ["b", "c"]], meshes=False)
    doc = json.loads(path.read_text())
    doc["obstructions"] = [{"direction": d, "blocks": [["b", "c"], ["c", "b"]]} for d in ("+X", "+Y", "+Z")]
    path.write_text(json.dumps(doc))
    return path


def test_an_interlocked_pair_is_one_line_the_detail_behind_verbose(tmp_path):
    path = _interlocked(tmp_path)
    done = run_aplan("stats", path)
    assert done.returncode == 1
    _one_line(done, "b and c block each other along every direction tried (+/-X, +/-Y, +/-Z)",
              "--group NAME=b,c", "--verbose")
    whole = run_aplan("stats", path, "--verbose")
    assert whole.returncode == 1 and "Look for overlapping geometry" in whole.stderr
    assert "--not-blocking" in whole.stderr and "Traceback" not in whole.stderr


def test_a_size_limit_is_one_line_naming_the_options(tmp_path):
    """The chain of 11 past --max-subassemblies 5: the size and the options by name; --verbose says why and
    what each does."""
    path = _product(tmp_path, "chain", [f"p{k}" for k in range(11)], [[f"p{k}", f"p{k + 1}"] for k in range(10)],
                    meshes=False)
    done = run_aplan("pomdp", path, "-o", tmp_path / "m.pomdpx", "--max-subassemblies", "5")
    assert done.returncode == 1 and not (tmp_path / "m.pomdpx").exists()
    _one_line(done, "AND/OR graph", "more than the limit of 5", "--max-subassemblies N")
    whole = run_aplan("pomdp", path, "-o", tmp_path / "m.pomdpx", "--max-subassemblies", "5", "--verbose")
    assert "What helps: --max-subassemblies N raises" in whole.stderr and "The reverse cut-set" in whole.stderr


def test_verbose_is_on_every_command():
    for command in ("stats", "intentions", "sequence", "pomdp", "solve", "simulate", "evaluate", "session",
                    "replay", "analyze", "markers", "synth", "fasteners"):
        assert "--verbose" in run_aplan(command, "--help").stdout, command
