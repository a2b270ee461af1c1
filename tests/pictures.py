"""What a person sees in a picture the tests saved (a 3D view, a panel, a plot): its pixels read with OpenCV and
classified by colour, so that a test asserts on the parts' colours, their share of the view and their extent,
never on the file's size in bytes (a PNG of a few coloured pixels compresses to the size of an empty one).

Colours are told apart by hue (the 3D view shades a part's colour from light to dark; its hue stays), with a
saturation and a brightness below which a pixel is grey (dimmed parts, edges, text) rather than coloured.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

__all__ = ["Picture", "assert_belief_plot", "hue_of", "read_picture"]


def hue_of(rgb) -> float:
    """The hue in degrees (0 to 360) of an RGB colour with components in 0..1."""
    pixel = np.array([[[round(255 * c) for c in rgb[::-1]]]], dtype=np.uint8)  # BGR, as OpenCV wants it
    return 2.0 * float(cv2.cvtColor(pixel, cv2.COLOR_BGR2HSV)[0, 0, 0])


@dataclass(frozen=True)
class Picture:
    """A picture as ``(height, width, 3)`` RGB bytes and its HSV form (hue in degrees, saturation and value in
    0..1)."""

    rgb: np.ndarray
    hue: np.ndarray
    saturation: np.ndarray
    value: np.ndarray

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return self.rgb.shape[1], self.rgb.shape[0]

    def crop(self, x: int, y: int, width: int, height: int) -> Picture:
        """The part of the picture from ``(x, y)`` (left, top), ``width`` by ``height`` pixels (clipped)."""
        window = np.s_[max(y, 0):y + height, max(x, 0):x + width]
        return Picture(self.rgb[window], self.hue[window], self.saturation[window], self.value[window])

    def differs_from(self, background=(255, 255, 255), tolerance: int = 8) -> np.ndarray:
        """Mask of the pixels more than ``tolerance`` (0..255, any channel) from ``background`` (RGB bytes)."""
        return np.abs(self.rgb.astype(np.int16) - np.array(background, dtype=np.int16)).max(axis=2) > tolerance

    def coloured(self, hue: float, width: float = 15.0, saturation: float = 0.5, value: float = 0.15) -> np.ndarray:
        """Mask of the pixels within ``width`` degrees of ``hue``, at least this saturated and bright."""
        apart = np.abs((self.hue - hue + 180.0) % 360.0 - 180.0)
        return (apart <= width) & (self.saturation >= saturation) & (self.value >= value)

    def grey(self, background=(255, 255, 255), saturation: float = 0.25) -> np.ndarray:
        """Mask of the pixels that are neither the background nor coloured: dimmed parts, edges, text."""
        return self.differs_from(background) & (self.saturation < saturation)

    def dark(self, value: float = 0.35) -> np.ndarray:
        """Mask of the dark pixels (text, lines)."""
        return self.value < value

    def share(self, mask: np.ndarray) -> float:
        """The fraction of the picture's pixels in ``mask``."""
        return float(mask.mean())

    def extent(self, mask: np.ndarray) -> tuple[float, float]:
        """The width and height of the bounding box of ``mask``, as fractions of the picture's (0, 0 if empty)."""
        ys, xs = np.nonzero(mask)
        if xs.size == 0:
            return 0.0, 0.0
        width, height = self.size
        return (int(xs.max()) - int(xs.min()) + 1) / width, (int(ys.max()) - int(ys.min()) + 1) / height

    def box(self, mask: np.ndarray) -> tuple[int, int, int, int] | None:
        """The bounding box ``(x0, y0, x1, y1)`` of ``mask`` in pixels (inclusive), None if empty."""
        ys, xs = np.nonzero(mask)
        return None if xs.size == 0 else (int(xs.min()), int(ys.min()), int(xs.max()), int(ys.max()))

    def colours(self, step: int = 16) -> int:
        """How many distinct colours there are, each channel rounded down to a multiple of ``step``."""
        quantised = (self.rgb // step).reshape(-1, 3).astype(np.int32)
        return int(np.unique(quantised[:, 0] * 65536 + quantised[:, 1] * 256 + quantised[:, 2]).size)


def assert_belief_plot(path) -> None:
    """A Fig. 7 heat map as a person sees it (:mod:`planner.decision.belief_plot`): 1300 px wide, the beliefs as
    viridis cells (green to yellow: measured 4.1 % of the pen session's picture), the most probable intention's
    red line (0.45 %), its labels (dark: 1.1 %)."""
    picture = read_picture(path)
    assert picture.size[0] == 1300, picture.size
    assert picture.share(picture.coloured(120.0, width=60, saturation=0.3, value=0.2)) >= 0.01
    assert picture.share(picture.coloured(5.0, width=12, saturation=0.6, value=0.5)) >= 0.001
    assert picture.share(picture.dark()) >= 0.004


def read_picture(path) -> Picture:
    """The picture at ``path`` (PNG or any format OpenCV reads); fails the test when it cannot be read."""
    bgr = cv2.imread(str(Path(path)), cv2.IMREAD_COLOR)
    assert bgr is not None, f"{path}: not a picture OpenCV can read"
    hsv = cv2.cvtColor(bgr, cv2.COLOR_BGR2HSV)
    return Picture(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB), 2.0 * hsv[..., 0].astype(np.float64),
                   hsv[..., 1] / 255.0, hsv[..., 2] / 255.0)
