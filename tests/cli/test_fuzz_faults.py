"""Faults around the commands (issue 14, items 2-4): output folders that are missing or read-only, a full disk,
damaged FreeCAD documents, and interrupts. Each named case runs the real command line (``planner.cli.main``,
or ``python -m planner`` where a signal is sent) and asserts exit status 1 or 2, a one-line message naming
the file and the fix, no traceback, and nothing left behind.

A full disk is simulated with the fault-injection seam of :mod:`planner.files` (``APLAN_FAULT_DISK_FULL=N``:
every write fails with ENOSPC after N bytes), since a small full tmpfs needs root. A read-only folder cannot
refuse root, so under root the write permission check is monkeypatched. Interrupt tests wait for events
(a progress line, a temporary folder, a child process), never for a time.
"""
from __future__ import annotations

import io
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import pytest
from conftest import PEN_MODELS, REPO, require_freecadcmd, require_shared

from planner.cli import main
from planner.decision.policy import read_policy
from planner.files import FAULT_DISK_FULL

PEN_FCSTD = PEN_MODELS / "simplified" / "asm_bourjault_ballpoint.FCStd"


def _tree(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*")}


def _run(capsys, args: list[str]) -> tuple[int, str, str]:
    try:
        code = main(args)
    except SystemExit as exc:  # argparse: usage errors
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def _assert_clean_failure(code: int, err: str, expected: str, codes=(1, 2)) -> None:
    assert code in codes, err
    assert "Traceback" not in err
    lines = [line for line in err.splitlines() if line.startswith("aplan: error:")]
    assert len(lines) == 1 and expected in lines[0], err


# name: (arguments, environment, the fragment the message must hold); {tmp}: the test's folder
OUTPUT_CASES = {
    "pomdp into a missing folder": (["pomdp", "pen", "-o", "nodir/m.pomdpx"], {}, "create the folder"),
    "markers into a missing folder": (["markers", "pen", "-o", "nodir/s.pdf"], {}, "create the folder"),
    "solve into a missing folder": (["solve", "pen", "-o", "nodir/p.policy", "--quiet"], {}, "create the folder"),
    "synth into a missing folder": (["synth", "chain", "4", "-o", "nodir/c.json"], {}, "create the folder"),
    "simulate plots into a missing folder": (["simulate", "pen", "--plot", "nodir/b"], {}, "create the folder"),
    "output is a folder": (["pomdp", "pen", "-o", "afolder"], {}, "a folder, but the output is a file"),
    "output under a file": (["pomdp", "pen", "-o", "afile/m.pomdpx"], {}, "is not a folder"),
    "pomdpx on a full disk": (["pomdp", "pen", "-o", "m.pomdpx"], {FAULT_DISK_FULL: "4096"}, "the disk is full"),
    ".pomdp on a full disk": (["pomdp", "pen", "-o", "m.pomdp"], {FAULT_DISK_FULL: "4096"}, "the disk is full"),
    "policy on a full disk": (["solve", "pen", "-o", "p.policy", "--force", "--quiet", "--trials", "20"],
                              {FAULT_DISK_FULL: "4096"}, "the disk is full"),
    "marker sheet (pdf) on a full disk": (["markers", "pen", "-o", "s.pdf"], {FAULT_DISK_FULL: "1000"},
                                          "the disk is full"),
    "marker sheet (png) on a full disk": (["markers", "pen", "-o", "s.png"], {FAULT_DISK_FULL: "1000"},
                                          "the disk is full"),
    "product file on a full disk": (["synth", "chain", "4", "-o", "c.json"], {FAULT_DISK_FULL: "100"},
                                    "the disk is full"),
    "belief plots on a full disk": (["simulate", "pen", "--planner", "offline", "--policy", "{tmp}/p.policy",
                                     "--plot", "b"], {FAULT_DISK_FULL: "1000"}, "the disk is full"),
    "second belief plot on a full disk": (["simulate", "pen", "--planner", "offline", "--policy", "{tmp}/p.policy",
                                           "--plot", "b"], {FAULT_DISK_FULL: "{between}"}, "b.svg"),
}


@pytest.fixture(scope="module")
def pen_policy(tmp_path_factory) -> Path:
    """A small policy for the pen (a few solver steps), for commands that need one."""
    folder = tmp_path_factory.mktemp("policy")
    assert main(["solve", "pen", "-o", str(folder / "p.policy"), "--quiet", "--trials", "20"]) == 0
    return folder / "p.policy"


@pytest.fixture(scope="module")
def plot_sizes(pen_policy) -> tuple[int, int]:
    """The sizes of the pen's belief plots (PNG, SVG) with ``pen_policy``, written on a disk with room."""
    folder = pen_policy.parent
    assert main(["simulate", "pen", "--planner", "offline", "--policy", str(pen_policy), "--plot",
                 str(folder / "b")]) == 0
    return (folder / "b.png").stat().st_size, (folder / "b.svg").stat().st_size


@pytest.mark.parametrize("name", list(OUTPUT_CASES))
def test_output_faults(name, tmp_path, monkeypatch, capsys, pen_policy, plot_sizes):
    arguments, env, expected = OUTPUT_CASES[name]
    png, svg = plot_sizes
    assert png < svg, "the second-plot case needs the SVG (written second) larger than the PNG"
    env = {key: value.replace("{between}", str((png + svg) // 2)) for key, value in env.items()}
    (tmp_path / "afolder").mkdir()
    (tmp_path / "afile").write_text("x")
    (tmp_path / "p.policy").write_bytes(pen_policy.read_bytes())
    monkeypatch.chdir(tmp_path)
    for key, value in env.items():
        monkeypatch.setenv(key, value)
    before = _tree(tmp_path)
    code, _, err = _run(capsys, [a.replace("{tmp}", str(tmp_path)) for a in arguments])
    _assert_clean_failure(code, err, expected)
    assert _tree(tmp_path) == before, "a file was left behind"


def test_read_only_folder(tmp_path, monkeypatch, capsys):
    folder = tmp_path / "ro"
    folder.mkdir()
    if os.geteuid() == 0:  # root writes anywhere: refuse as a read-only folder would
        real = os.access
        monkeypatch.setattr("planner.files.os.access",
                            lambda p, mode, **kw: False if Path(p) == folder else real(p, mode, **kw))
    else:
        folder.chmod(0o555)
    code, _, err = _run(capsys, ["pomdp", "pen", "-o", str(folder / "m.pomdpx")])
    _assert_clean_failure(code, err, "is not writable")
    assert _tree(folder) == set()


def test_refusal_while_writing(tmp_path, monkeypatch, capsys):
    """The folder was fine when checked, then refuses the file (permissions changed meanwhile)."""
    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr("planner.files.os.open", refuse)
    code, _, err = _run(capsys, ["pomdp", "pen", "-o", str(tmp_path / "m.pomdpx")])
    _assert_clean_failure(code, err, "Permission denied")
    assert _tree(tmp_path) == set()


def test_outputs_respect_the_umask(tmp_path):
    from planner.files import make_folder_beside, write_atomic

    old = os.umask(0o022)
    try:
        write_atomic(tmp_path / "a.txt", "a")
        folder = make_folder_beside(tmp_path / "bundle")
        os.umask(0o077)
        write_atomic(tmp_path / "b.txt", "b")
        private = make_folder_beside(tmp_path / "other")
    finally:
        os.umask(old)
    assert (tmp_path / "a.txt").stat().st_mode & 0o777 == 0o644
    assert folder.stat().st_mode & 0o777 == 0o755 and folder.name.startswith(".bundle.")
    assert (tmp_path / "b.txt").stat().st_mode & 0o777 == 0o600
    assert private.stat().st_mode & 0o777 == 0o700


# --- damaged FreeCAD documents -------------------------------------------------------------------------------

def _shape_files(document: bytes) -> dict[str, str]:
    """Object label -> its shape member, read from Document.xml with a plain XML parser (the ground truth)."""
    from lxml import etree

    root = etree.fromstring(document)
    out = {}
    for obj in root.iter("Object"):
        label = obj.find("Properties/Property[@name='Label']/String")
        part = obj.find("Properties/Property[@name='Shape']/Part")
        if label is not None and part is not None and part.get("file"):
            out[label.get("value")] = part.get("file")
    return out


@pytest.fixture(scope="module")
def damaged(tmp_path_factory):
    """A truncated copy of the pen's assembly and one with a corrupt Document.xml, with the labels each loses:
    truncated, the objects whose shape member does not end before the cut; corrupt, the part objects whose
    data in Document.xml starts after the damage."""
    source = require_shared(PEN_FCSTD).read_bytes()
    folder = tmp_path_factory.mktemp("damaged")
    archive = zipfile.ZipFile(io.BytesIO(source))
    document = archive.read("Document.xml")
    files = _shape_files(document)
    assert len(files) == 6  # the pen's six parts
    cut = 10_000
    ends = {info.filename: info.header_offset + 30 + len(info.filename) + len(info.extra) + info.compress_size
            for info in archive.infolist()}
    assert ends["Document.xml"] < cut
    truncated = folder / "truncated.FCStd"
    truncated.write_bytes(source[:cut])
    lost_truncated = {label for label, member in files.items() if ends[member] > cut}
    middle = len(document) // 2
    corrupt_xml = document[:middle] + b"<<&&" + document[middle + 4:]
    corrupt = folder / "corrupt.FCStd"
    with zipfile.ZipFile(corrupt, "w", zipfile.ZIP_DEFLATED) as out:
        for info in archive.infolist():
            out.writestr(info, corrupt_xml if info.filename == "Document.xml" else archive.read(info))
    lost_corrupt = {label for label in files if document.index(f'<String value="{label}"/>'.encode()) > middle}
    assert lost_truncated and lost_corrupt and len(lost_truncated) < 6 and len(lost_corrupt) < 6
    return {"truncated": (truncated, lost_truncated), "corrupt": (corrupt, lost_corrupt)}


@pytest.mark.parametrize("kind", ["truncated", "corrupt"])
@pytest.mark.parametrize("command", ["export-freecad", "stats"])
def test_damaged_document_is_an_error_naming_each_object(kind, command, damaged, tmp_path, capsys):
    path, lost = damaged[kind]
    arguments = [command, str(path)] + (["-o", str(tmp_path / "bundle")] if command == "export-freecad" else [])
    code, out, err = _run(capsys, arguments)
    _assert_clean_failure(code, err, "the document is damaged")
    named = {label for label in _shape_files(zipfile.ZipFile(PEN_FCSTD).read("Document.xml")) if label in err}
    assert named == lost
    assert "--skip-damaged" in err and _tree(tmp_path) == set()
    # only an option the command takes: stats has no --skip-damaged, export-freecad has
    assert ("`aplan export-freecad MODEL -o BUNDLE --skip-damaged`" in err) == (command == "stats")


def test_truncation_anywhere_names_exactly_the_lost_objects(tmp_path):
    """Brute force over cut points: the objects named are those whose shape member does not end before the cut
    (computed from the intact archive's directory); a cut inside Document.xml is an error of its own."""
    from freecad_aplan.archive import DamagedDocumentError, document_damage

    source = require_shared(PEN_FCSTD).read_bytes()
    archive = zipfile.ZipFile(io.BytesIO(source))
    files = _shape_files(archive.read("Document.xml"))
    ends = {info.filename: info.header_offset + 30 + len(info.filename) + len(info.extra) + info.compress_size
            for info in archive.infolist()}
    path = tmp_path / "cut.FCStd"
    for cut in range(0, len(source), 211):
        path.write_bytes(source[:cut])
        if ends["Document.xml"] > cut:
            with pytest.raises(DamagedDocumentError, match="Document.xml|not a zip archive"):
                document_damage(path)
            continue
        named = {d.label for d in document_damage(path)}
        assert named == {label for label, member in files.items() if ends[member] > cut}, cut


def test_the_intact_document_has_no_damage():
    from freecad_aplan.archive import document_damage

    assert document_damage(require_shared(PEN_FCSTD)) == []


_LINKING = b"""<?xml version='1.0' encoding='utf-8'?>
<Document SchemaVersion="4" ProgramVersion="0.20" FileVersion="1">
  <Objects Count="1">
    <Object type="App::Link" name="Post" id="1"/>
  </Objects>
  <ObjectData Count="1">
    <Object name="Post">
      <Properties Count="2">
        <Property name="Label" type="App::PropertyString"><String value="Post"/></Property>
        <Property name="LinkedObject" type="App::PropertyXLink">
          <XLink file="%s" stamp="2026-12-02T01:10:49Z" name="Part"/>
        </Property>
        <Property name="PlacementList" type="App::PropertyPlacementList">
          <PlacementList file="PlacementList"/>
        </Property>
      </Properties>
    </Object>
  </ObjectData>
</Document>
"""


def _linking(folder, target: str):
    path = folder / "asm.FCStd"
    with zipfile.ZipFile(path, "w") as out:
        out.writestr("Document.xml", _LINKING % target.encode())
        out.writestr("PlacementList", b"\0\0\0\0")
    return path


def test_a_link_to_another_document_is_no_missing_member(tmp_path, damaged):
    """<XLink file="post.FCStd"> names a document beside this one (Assembly4, A2plus, App::Link), not a member
    of the archive: no damage when it is there; the link named when it is missing or damaged itself."""
    from freecad_aplan.archive import document_damage

    path = _linking(tmp_path, "post.FCStd")
    shutil.copy(PEN_FCSTD, tmp_path / "post.FCStd")
    assert document_damage(path) == []
    (tmp_path / "post.FCStd").unlink()
    (damage,) = document_damage(path)
    assert (damage.name, damage.problem) == ("Post", f"it links to post.FCStd, which is not in {tmp_path} (copy it "
                                                     "beside asm.FCStd)")
    shutil.copy(damaged["truncated"][0], tmp_path / "post.FCStd")
    (damage,) = document_damage(path)
    assert damage.problem.startswith("it links to post.FCStd, which is damaged: ")
    assert _linking(tmp_path, "") and document_damage(path) == []  # an empty XLink: this document's own object


def test_skip_damaged_exports_the_rest_with_a_warning(damaged, tmp_path):
    require_freecadcmd()
    path, lost = damaged["truncated"]
    done = subprocess.run([sys.executable, "-m", "planner", "export-freecad", str(path), "-o", str(tmp_path / "b"),
                           "--skip-damaged", "--engine", "none"], capture_output=True, text=True, timeout=300,
                          cwd=REPO)
    assert done.returncode == 0, done.stderr
    warning = [line for line in done.stderr.splitlines() if "left out" in line]
    assert len(warning) == 1 and all(label in warning[0] for label in lost)
    exported = {p.stem for p in (tmp_path / "b" / "meshes").glob("*.stl")}
    assert len(exported) == 6 - len(lost) and not exported & lost
    assert (tmp_path / "b").stat().st_mode & 0o777 == 0o777 & ~_umask()


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


# --- interrupts ----------------------------------------------------------------------------------------------

def _wait_for(condition, what: str, polls: int = 1200):
    """Poll ``condition`` every 0.1 s, at most ``polls`` times (a bound on work, not a timing assertion)."""
    for _ in range(polls):
        value = condition()
        if value:
            return value
        time.sleep(0.1)
    pytest.fail(f"never happened: {what}")


def _children(pid: int) -> list[int]:
    found = subprocess.run(["pgrep", "-P", str(pid)], capture_output=True, text=True).stdout.split()
    return [int(p) for p in found]


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/status") as handle:
            return "\nState:\tZ" not in handle.read()  # a zombie is dead, waiting for a reaper
    except FileNotFoundError:
        return False


def test_session_log_on_a_full_disk(tmp_path, monkeypatch, capsys):
    """A session whose log fills the disk (the seam fails the write that passes N bytes after writing what
    fits, as a real full disk does): exit 1 with one line naming the log, no traceback; the log is cut back
    to its last complete event, so aplan replay still reads the events before the failure."""
    monkeypatch.chdir(tmp_path)
    session = ["session", "pen", "--keyboard", "--expansions", "20", "--log"]
    monkeypatch.setattr(sys, "stdin", io.StringIO(""))  # no operator input: the source ends at once
    code, _, err = _run(capsys, [*session, "whole.jsonl"])
    assert code == 1 and "Traceback" not in err  # the source ended: not assembled
    whole = (tmp_path / "whole.jsonl").read_bytes().splitlines(keepends=True)
    events = [line.split(b'"event": "')[1].split(b'"')[0] for line in whole]
    assert events[:2] == [b"start", b"action"], events
    # The disk fills 50 bytes into the second event (its 'action').
    monkeypatch.setenv(FAULT_DISK_FULL, str(len(whole[0]) + 50))
    monkeypatch.setattr(sys, "stdin", io.StringIO(""))
    code, _, err = _run(capsys, [*session, "full.jsonl"])
    _assert_clean_failure(code, err, "full.jsonl: cannot write the session log (No space left on device)")
    assert "free some space" in err and "keeps the 1 event before" in err
    assert (tmp_path / "full.jsonl").read_bytes().endswith(b"\n")
    kept = (tmp_path / "full.jsonl").read_bytes().splitlines(keepends=True)
    assert len(kept) == 1 and kept[0].startswith(b'{"event": "start"')
    monkeypatch.delenv(FAULT_DISK_FULL)
    code, out, err = _run(capsys, ["replay", "full.jsonl"])
    assert code == 0 and "beliefs reproduced at all 0 steps" in out and "ended: no end event" in out, err
    assert _tree(tmp_path) == {"whole.jsonl", "full.jsonl"}


def _progress_lower(seen: bytes) -> list[float]:
    """The lower bounds of the solver's complete progress lines so far."""
    return [float(x) for x in re.findall(r"lower (-?\d+\.\d+)  upper", seen.decode())]


def _solve_interrupted(argv: list[str], signum: int, timeout: float) -> tuple[int, str]:
    """``aplan solve ARGV`` in a process of its own, sent ``signum`` once its lower bound has moved (a policy
    better than the blind ones, which would not be written): its exit status and everything it printed."""
    process = subprocess.Popen([sys.executable, "-m", "planner", "solve", *argv], cwd=REPO, stderr=subprocess.PIPE,
                               stdout=subprocess.PIPE)
    seen = b""
    while len(set(_progress_lower(seen))) < 2:
        chunk = process.stderr.read1(256)
        assert chunk, "the solver ended before it was interrupted: " + seen.decode()
        seen += chunk
    process.send_signal(signum)
    out, err = process.communicate(timeout=timeout)
    return process.returncode, (seen + err).decode()


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_interrupted_solve_keeps_the_best_policy(signum, tmp_path):
    target = tmp_path / "p.policy"
    code, message = _solve_interrupted(["pen", "-o", str(target), "--time-limit", "600", "--precision", "0"], signum,
                                       timeout=120)
    assert code == 128 + signum, message
    assert "Traceback" not in message and "wrote the best policy so far" in message
    assert _tree(tmp_path) == {"p.policy"}  # renamed into place, no temporary file
    from planner import api

    policy = read_policy(target, api.tables(api.load_model("pen")))
    assert policy.alphas.shape[0] >= 22  # at least the blind policies, one per action


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_interrupted_lumped_solve_bounded_by_trials(signum, tmp_path):
    """Issue 22 item 4: a solve bounded by trials (far more than it can do before the signal), interrupted once
    its lower bound has left the blind policies' value: the policy so far is written, valid for the lumped
    model, and the exit status is 128 + the signal."""
    from planner import api
    from planner.product.synthetic import chain_product

    product = tmp_path / "chain6.json"
    assert main(["synth", "chain", "6", "-o", str(product)]) == 0
    target = tmp_path / "p.policy"
    code, message = _solve_interrupted([str(product), "--lumped", "-o", str(target), "--trials", "100000000",
                                        "--time-limit", "1000000", "--precision", "0"], signum, timeout=300)
    assert code == 128 + signum, message
    assert "Traceback" not in message and "wrote the best policy so far" in message
    assert _tree(tmp_path) == {"chain6.json", "p.policy"}
    model = api.lumped_model(chain_product(6))
    read_policy(target, model.pomdp).check(model.pomdp)


def test_deferred_interrupts_nest():
    """One flag for a computation made of parts (api.solve's warm start, then the solver): a nested block
    shares the outer one's flag and handlers, and the first signal is deferred, not raised."""
    from planner.interrupts import deferred_interrupts

    with deferred_interrupts() as outer:
        with deferred_interrupts() as inner:
            assert inner is outer
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(1000):  # the handler runs between bytecodes
                if inner():
                    break
            assert inner() == signal.SIGINT
        assert outer() == signal.SIGINT


def test_deferred_interrupt_in_process():
    """The solver's own contract: an interrupt after the k-th step ends it with the policy so far; without
    keep_on_interrupt it propagates. Work-bounded: the interrupt comes from the progress callback."""
    from planner import api
    from planner.decision.solvers.point_based import PointBasedSolver

    model = api.tables(api.load_model("pen"))
    steps = []

    def progress(*_):
        steps.append(1)
        if len(steps) == 5:
            os.kill(os.getpid(), signal.SIGINT)

    result = PointBasedSolver(time_limit=None, precision=0, keep_on_interrupt=True).solve(model, progress)
    assert result.interrupted == signal.SIGINT and len(steps) == 5
    result.policy.check(model)
    steps.clear()
    with pytest.raises(KeyboardInterrupt):
        PointBasedSolver(time_limit=None, precision=0).solve(model, progress)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_interrupted_stats_of_a_document_kills_freecad_and_cleans_up(signum, tmp_path):
    require_freecadcmd()
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    model = tmp_path / "pen.FCStd"
    model.write_bytes(require_shared(PEN_FCSTD).read_bytes())
    process = subprocess.Popen([sys.executable, "-m", "planner", "stats", str(model)], cwd=REPO,
                               env={**os.environ, "TMPDIR": str(temporary)}, stdout=subprocess.DEVNULL,
                               stderr=subprocess.PIPE)
    child = _wait_for(lambda: _children(process.pid), "FreeCADCmd started")[0]
    _wait_for(lambda: list(temporary.iterdir()), "the temporary bundle folder made")
    process.send_signal(signum)
    _, err = process.communicate(timeout=120)
    assert process.returncode == 128 + signum, err.decode()
    assert "Traceback" not in err.decode()
    assert list(temporary.iterdir()) == []
    assert not _alive(child)


def test_sigterm_on_export_removes_the_partial_bundle(tmp_path):
    require_freecadcmd()
    model = tmp_path / "pen.FCStd"
    model.write_bytes(require_shared(PEN_FCSTD).read_bytes())
    process = subprocess.Popen([sys.executable, "-m", "planner", "export-freecad", str(model), "-o",
                                str(tmp_path / "bundle")], cwd=REPO, stdout=subprocess.DEVNULL,
                               stderr=subprocess.PIPE)
    _wait_for(lambda: [p for p in tmp_path.iterdir() if p.name.endswith(".partial")], "the partial bundle made")
    child = _wait_for(lambda: _children(process.pid), "FreeCADCmd started")[0]
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=120)
    assert process.returncode == 128 + signal.SIGTERM and "Traceback" not in err.decode()
    assert _tree(tmp_path) == {"pen.FCStd"}
    assert not _alive(child)


#: ``aplan ARGS`` that stops inside trimesh's ``try: from . import voxel / except BaseException`` (an optional
#: import that swallows everything), says so on standard error and goes on when a line comes on standard input.
_PAUSED_IN_TRIMESH = r"""
import sys
from importlib.abc import MetaPathFinder


class PauseInTrimesh(MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name == "trimesh.voxel":
            print("paused in trimesh's guarded import", file=sys.stderr, flush=True)
            sys.stdin.readline()
        return None


sys.meta_path.insert(0, PauseInTrimesh())
from planner.cli import main
sys.exit(main(sys.argv[1:]))
"""


def _pending_signals(pid: int) -> int:
    """The signals sent to ``pid`` and not yet delivered (its own and its thread group's)."""
    with open(f"/proc/{pid}/status") as handle:
        fields = dict(line.split(":", 1) for line in handle if ":" in line)
    return int(fields["SigPnd"], 16) | int(fields["ShdPnd"], 16)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_during_an_import_that_swallows_everything_is_not_lost(signum, tmp_path):
    """Issue 22: trimesh guards its optional imports with ``except BaseException``; a Ctrl-C or SIGTERM that
    came then was swallowed and the command ran to its end (exit 0, the output written). Now it ends with
    128 + N, one line, no traceback, no output: the signal is sent while the import is paused there, and the
    import goes on only once the signal has been delivered (/proc: nothing pending)."""
    target = tmp_path / "out.json"
    process = subprocess.Popen([sys.executable, "-c", _PAUSED_IN_TRIMESH, "analyze",
                                str(REPO / "resources" / "examples" / "pen" / "pen.json"), "-o", str(target)],
                               cwd=REPO, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    seen = b""
    while b"guarded import\n" not in seen:  # the whole line: a signal in the middle of print() would cut it
        chunk = process.stderr.read1(256)
        assert chunk, f"the command ended before it reached trimesh's import: {seen.decode()}"
        seen += chunk
    process.send_signal(signum)
    _wait_for(lambda: not _pending_signals(process.pid), "the signal delivered")
    out, err = process.communicate(b"\n", timeout=120)
    message = (seen + err).decode()
    assert process.returncode == 128 + signum, message
    assert "Traceback" not in message
    assert message.splitlines()[-1] == f"aplan: interrupted ({signal.Signals(signum).name}): nothing was written"
    assert _tree(tmp_path) == set() and out == b""  # no output, no temporary file


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_an_interrupted_session_keeps_its_log_and_exits_128_plus_n(signum, tmp_path):
    """A keyboard session signalled while it waits for the operator: 128 + N (it used to exit 1: the session
    caught the interrupt and returned), one line saying the log is kept, the log ended by an interrupted event,
    nothing else written."""
    log = tmp_path / "s.jsonl"
    process = subprocess.Popen([sys.executable, "-m", "planner", "session", "pen", "--keyboard", "--log", str(log),
                                "--expansions", "20"], cwd=REPO, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE)
    seen = b""
    while b"operator picked" not in seen:  # the first prompt: the session waits for a line
        chunk = process.stderr.read1(256)
        assert chunk, f"the session ended before it asked: {seen.decode()}"
        seen += chunk
    process.send_signal(signum)
    out, err = process.communicate(timeout=120)
    message = (seen + err).decode()
    assert process.returncode == 128 + signum and "Traceback" not in message, message
    assert message.splitlines()[-1] == (f"aplan: interrupted ({signal.Signals(signum).name}): the session log "
                                        f"{log} holds every step before it")
    events = [json.loads(line) for line in log.read_text().splitlines()]
    assert events[0]["event"] == "start" and events[-1]["event"] == "end"
    assert events[-1]["reason"] == "interrupted" and _tree(tmp_path) == {"s.jsonl"}


def test_random_damage_is_named_or_harmless(tmp_path):
    """Property: bytes overwritten anywhere in the archive, and maybe a truncation, give a list of damaged
    objects or a DamagedDocumentError, never another exception (hypothesis draws the places, the bytes and the
    cut; before this test, a flipped byte could raise NotImplementedError or RuntimeError from zipfile)."""
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    from freecad_aplan.archive import DamagedDocumentError, document_damage

    source = require_shared(PEN_FCSTD).read_bytes()
    path = tmp_path / "hit.FCStd"

    @settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
    @given(st.lists(st.tuples(st.integers(0, len(source) - 1), st.binary(min_size=1, max_size=8)), min_size=1,
                    max_size=4), st.one_of(st.none(), st.integers(0, len(source))))
    def damage(hits, cut):
        data = bytearray(source)
        for at, junk in hits:
            data[at:at + len(junk)] = junk
        path.write_bytes(bytes(data[:cut]))
        try:
            found = document_damage(path)
        except DamagedDocumentError:
            return
        assert all(d.name and d.problem for d in found)

    damage()


# Issue 22: under an address-space limit of 5 GiB (a machine with little memory), each command that would pass
# the memory budget is refused at once with its estimate: no MemoryError traceback, nothing written.
ADDRESS_SPACE_CASES = {
    "simulate complete 12": (["simulate", "{product}", "--sequence", "0"], "online planner"),
    "pomdp --lumped complete 12": (["pomdp", "{product}", "--lumped", "-o", "m.pomdpx"], "lumped model"),
}


@pytest.mark.parametrize("name", list(ADDRESS_SPACE_CASES))
def test_refused_under_an_address_space_limit(name, tmp_path, capsys):
    import resource

    product = tmp_path / "complete12.json"
    assert _run(capsys, ["synth", "complete", "12", "-o", str(product)])[0] == 0
    arguments, expected = ADDRESS_SPACE_CASES[name]
    before = _tree(tmp_path)
    limit = 5 * 2 ** 30
    done = subprocess.run([sys.executable, "-m", "planner", *[a.format(product=product) for a in arguments]],
                          capture_output=True, text=True, cwd=tmp_path, timeout=600,
                          preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_AS, (limit, limit)))
    _assert_clean_failure(done.returncode, done.stderr, expected)
    assert "complete12.json" in done.stderr and "memory budget" in done.stderr
    assert _tree(tmp_path) == before, "a file was left behind"
