"""The printable marker sheet: every part's and tool's tray marker, with its name and id, on A4 pages."""
from __future__ import annotations

from pathlib import Path

from ..errors import PlannerError
from ..files import open_atomic, save_figure
from ..product import Product
from .tray import marker_image
from .vision.markers import MarkerMap, marker_map

__all__ = ["write_marker_sheet"]


def write_marker_sheet(product: Product, path: str | Path, marker_mm: float = 40.0) -> int:
    """Write the markers of ``product`` (one per part and tool, with its name and id) on A4 pages as a PDF
    or a PNG (by the suffix; a PNG holds the first page only when they do not fit one), atomically.

    Returns the number of markers. Markers are ``marker_mm`` wide when printed at 100 %.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".pdf", ".png"):
        raise PlannerError(f"{path}: the marker sheet is written as .pdf or .png; change the file name")
    markers = marker_map(product, require_all=False)
    pages = _sheet_pages(product, markers, marker_mm)
    if suffix == ".png":
        save_figure(pages[0], path, dpi=300)
    else:
        from matplotlib.backends.backend_pdf import PdfPages

        with open_atomic(path) as handle:
            pdf = PdfPages(handle)  # closed only on success: closing after a write error hides the error
            for page in pages:
                pdf.savefig(page)
            pdf.close()
    return len(markers.items)


_A4 = (210.0, 297.0)  # page width and height, mm


def _sheet_pages(product: Product, markers: MarkerMap, marker_mm: float) -> list:
    """The marker sheet's pages as matplotlib ``Figure`` objects (no pyplot: its state is process-wide), as many
    markers per A4 page as fit in cells of ``marker_mm`` + 20 by ``marker_mm`` + 22 mm under a 22 mm title."""
    from matplotlib.figure import Figure

    page_w, page_h = _A4
    cell_w, cell_h = marker_mm + 20.0, marker_mm + 22.0
    columns = max(1, int((page_w - 20) // cell_w))
    rows = max(1, int((page_h - 30) // cell_h))
    entries = sorted(markers.items.items())
    chunks = [entries[i:i + columns * rows] for i in range(0, len(entries), columns * rows)]
    labels = {p.id: p.label or p.id for p in product.parts} | {t.id: t.label or t.id for t in product.tools}
    figures = []
    for number, chunk in enumerate(chunks, start=1):
        fig = Figure(figsize=(page_w / 25.4, page_h / 25.4))
        fig.text(0.5, 1 - 12 / page_h, f"{product.name or 'APLAN product'}: tray markers ({markers.dictionary}, "
                 f"{marker_mm:g} mm){f', page {number}/{len(chunks)}' if len(chunks) > 1 else ''}",
                 ha="center", va="center", fontsize=10)
        for k, (marker, name) in enumerate(chunk):
            left = 10 + (k % columns) * cell_w + (cell_w - marker_mm) / 2
            top = 22 + (k // columns) * cell_h
            ax = fig.add_axes((left / page_w, 1 - (top + marker_mm) / page_h, marker_mm / page_w, marker_mm / page_h))
            ax.imshow(marker_image(markers.dictionary, marker, 240), cmap="gray", vmin=0, vmax=255,
                      interpolation="nearest")
            ax.set_axis_off()
            kind = "tool" if name in markers.tools else "part"
            fig.text((left + marker_mm / 2) / page_w, 1 - (top + marker_mm + 6) / page_h,
                     f"{labels.get(name, name)} ({kind} {name!r}, marker {marker})", ha="center", va="center",
                     fontsize=8)
        figures.append(fig)
    return figures
