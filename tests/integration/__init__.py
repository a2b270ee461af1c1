"""Tests through real FreeCAD and the command line, end to end (a package, so that the workbench's tests
can import :mod:`.freecad_tools`)."""
