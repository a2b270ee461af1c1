"""The disk the suite writes on: refuse to start when too little is free, and say how much the suite used.

A CI run once failed at 98 % with "No space left on device" in a test that had nothing wrong with it. The
suite writes its files (pytest's ``tmp_path``, the background jobs' folders, FreeCAD's homes) in the temporary
folder; what a full run takes at most there is measured by :class:`Watch` and printed at the end, and
:data:`NEEDED_MB` is that figure with a margin. A disk with less free fails at once with this figure instead of
as a random test's error minutes later.
"""
from __future__ import annotations

import shutil
import tempfile
import threading

# A fresh clone's whole CI run took about 350 MB of the disk at once while pytest ran (df sampled every 5 s beside
# it, 2026-12-02; 200 MB of it in /tmp); some margin above that, for products and logs that grow.
NEEDED_MB = 500
SAMPLE_SECONDS = 2.0


def free_mb(folder: str | None = None) -> float:
    """Megabytes free on the disk of ``folder`` (the temporary folder by default)."""
    return shutil.disk_usage(folder or tempfile.gettempdir()).free / 2**20


def shortage(needed_mb: float = NEEDED_MB) -> str | None:
    """Why the suite cannot run on this disk (what is free, what it needs, how to fix), or None."""
    free = free_mb()
    if free >= needed_mb:
        return None
    return (f"only {free:.0f} MB are free on the disk of {tempfile.gettempdir()}; the test suite writes up to "
            f"about {needed_mb} MB there: free some space, or point TMPDIR at a disk with more")


class Watch:
    """The least free space seen on the temporary folder's disk while the suite runs (sampled every
    :data:`SAMPLE_SECONDS` by a daemon thread: one ``statvfs`` call each, nothing written)."""

    def __init__(self, needed_mb: float = NEEDED_MB) -> None:
        self.needed_mb = needed_mb  # what the session was checked against (fewer tests need less)
        self.start_mb = self.least_mb = free_mb()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._sample, name="disk watch", daemon=True)
        self._thread.start()

    def _sample(self) -> None:
        while not self._stop.wait(SAMPLE_SECONDS):
            self.least_mb = min(self.least_mb, free_mb())

    def summary(self) -> str:
        """One line: free at the start, at the least, and the most the suite took at once."""
        self._stop.set()
        self.least_mb = min(self.least_mb, free_mb())
        return (f"disk ({tempfile.gettempdir()}): {self.start_mb:.0f} MB free at the start, {self.least_mb:.0f} MB "
                f"at the least: the suite took up to {self.start_mb - self.least_mb:.0f} MB at once "
                f"(it refuses to start below {self.needed_mb:.0f} MB)")
