"""The workbench's GUI: commands (:mod:`.commands`), task panels and dialogs (:mod:`.panels`), background
jobs (:mod:`.jobs`). Imported only inside FreeCAD's GUI, when the workbench is activated."""
