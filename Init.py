# APLAN addon, loaded by FreeCAD (GUI and FreeCADCmd) from its Mod folder. FreeCAD puts this folder on
# sys.path, so the packages `freecad_aplan` (FreeCAD side) and `planner` (headless planner) import as they are.
# Nothing is registered without the GUI: batch use goes through `freecad_aplan` directly.
