"""The suite's disk check (tests/disk.py): what it says when the disk is short, and what its watch reports."""
from __future__ import annotations

import tempfile

import disk


def test_a_short_disk_is_refused_with_what_is_free_and_what_is_needed():
    assert disk.shortage(0) is None
    needed = int(disk.free_mb() * 4) + 1000
    message = disk.shortage(needed)
    assert message is not None
    assert tempfile.gettempdir() in message and f"about {needed} MB" in message and "TMPDIR" in message


def test_the_watch_reports_the_least_free_space_it_saw(monkeypatch):
    readings = iter([900.0, 700.0, 800.0])  # at the start, a sample, at the summary
    monkeypatch.setattr(disk, "free_mb", lambda folder=None: next(readings))
    monkeypatch.setattr(disk, "SAMPLE_SECONDS", 3600.0)  # no sample from the thread: the test takes them
    watch = disk.Watch()
    watch.least_mb = min(watch.least_mb, disk.free_mb())
    line = watch.summary()
    assert "900 MB free at the start, 700 MB at the least" in line and "took up to 200 MB" in line
