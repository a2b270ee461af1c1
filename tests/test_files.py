"""Binary outputs written atomically (planner.files.open_atomic, save_figure); write_atomic is tested with the
product files (tests/product/test_product.py)."""
from __future__ import annotations

import stat
import subprocess
import sys

import pytest

from planner.files import open_atomic, save_figure


def test_open_atomic_replaces_on_success_only(tmp_path):
    target = tmp_path / "out.bin"
    target.write_bytes(b"old")
    with pytest.raises(RuntimeError), open_atomic(target) as handle:
        handle.write(b"half of the new")
        raise RuntimeError("the disk is full")
    assert target.read_bytes() == b"old" and [p.name for p in tmp_path.iterdir()] == ["out.bin"]
    with open_atomic(target) as handle:
        handle.write(b"new")
        assert target.read_bytes() == b"old"  # not in place before the block ends
    assert target.read_bytes() == b"new" and [p.name for p in tmp_path.iterdir()] == ["out.bin"]


def test_open_atomic_gives_the_usual_permissions(tmp_path):
    """0o666 less the umask, as any new file (mkstemp alone would make it private); in a process of its own,
    so the test does not change the umask of the process running the tests."""
    script = ("import sys\nfrom planner.files import open_atomic\n"
              "with open_atomic(sys.argv[1]) as h:\n    h.write(b'x')\n")
    done = subprocess.run([sys.executable, "-c", script, str(tmp_path / "shared.bin")], umask=0o027,
                          capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert stat.S_IMODE((tmp_path / "shared.bin").stat().st_mode) == 0o640


def test_save_figure_takes_the_format_from_the_suffix(tmp_path):
    from matplotlib.figure import Figure

    figure = Figure(figsize=(2, 1))
    figure.subplots().plot([0, 1], [1, 0])
    assert save_figure(figure, tmp_path / "f.svg") == str(tmp_path / "f.svg")
    save_figure(figure, tmp_path / "f.PNG", dpi=50)
    assert b"<svg" in (tmp_path / "f.svg").read_bytes()[:400]
    assert (tmp_path / "f.PNG").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ValueError, match="not supported"):
        save_figure(figure, tmp_path / "f.docx")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.PNG", "f.svg"]


def test_building_folder_replaces_a_folder_on_success_only(tmp_path):
    """The one folder swap (bundles): built beside the target, renamed into place at the end; a failure leaves
    the old folder as it was and nothing else behind."""
    from planner.files import building_folder

    target = tmp_path / "bundle"
    target.mkdir()
    (target / "old.txt").write_text("old")
    with pytest.raises(RuntimeError), building_folder(target) as work:
        (work / "new.txt").write_text("half")
        assert work.parent == tmp_path and work.name.startswith(".bundle.")
        raise RuntimeError("the export failed")
    assert sorted(p.name for p in target.iterdir()) == ["old.txt"] and [p.name for p in tmp_path.iterdir()] == ["bundle"]
    with building_folder(target) as work:
        (work / "new.txt").write_text("new")
        assert (target / "old.txt").is_file()  # not in place before the block ends
    assert sorted(p.name for p in target.iterdir()) == ["new.txt"] and [p.name for p in tmp_path.iterdir()] == ["bundle"]


def test_building_folder_makes_a_new_folder(tmp_path):
    from planner.files import building_folder

    with building_folder(tmp_path / "fresh") as work:
        (work / "a").write_text("a")
    assert (tmp_path / "fresh" / "a").read_text() == "a" and [p.name for p in tmp_path.iterdir()] == ["fresh"]
