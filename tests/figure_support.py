"""A check shared by the tests of the pictures (assembly figures, the Fig. 7 plot, the marker sheet)."""
from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def pyplot_untouched(monkeypatch) -> Iterator[None]:
    """Fails when the code inside switches matplotlib's process-wide backend or leaves pyplot figures open:
    the planner also draws inside FreeCAD's GUI process, whose backend is not ours to change."""
    import matplotlib
    import matplotlib.pyplot as plt

    def switch(*args, **kwargs):
        raise AssertionError("matplotlib's backend is process-wide: draw on a matplotlib.figure.Figure instead")

    with monkeypatch.context() as patch:
        patch.setattr(matplotlib, "use", switch)
        patch.setattr(plt, "switch_backend", switch)
        before = plt.get_fignums()
        yield
        assert plt.get_fignums() == before
