"""The FreeCAD side of APLAN: everything that imports FreeCAD (reading documents, GUI, batch export).

It turns FreeCAD documents into product bundles and calls the headless ``planner``; the planner never
imports this package. Importing this package itself does not import FreeCAD, so its helpers can be used
(and tested) from any Python.
"""
from __future__ import annotations

import os

__all__ = ["ADDON_DIR", "icon_path"]

ADDON_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def icon_path(name: str) -> str:
    """The path of an icon shipped in ``resources/icons``."""
    return os.path.join(ADDON_DIR, "resources", "icons", name)
