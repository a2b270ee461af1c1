# APLAN workbench registration (runs when the FreeCAD GUI starts). FreeCAD executes this file without
# __file__, so paths come from the freecad_aplan package.
import FreeCADGui


class AplanWorkbench(FreeCADGui.Workbench):
    """APLAN: designer intent, assembly plans and operator intentions for human-robot collaboration."""

    MenuText = "APLAN"
    ToolTip = "Assembly plans and operator intentions for human-robot collaborative assembly"

    def __init__(self):
        import freecad_aplan

        self.__class__.Icon = freecad_aplan.icon_path("aplan.svg")

    def Initialize(self):
        # Commands are imported here, when the workbench is first activated, not at FreeCAD start-up.
        from freecad_aplan.gui import commands

        # The Addon Manager installs only the packages on FreeCAD's allowed list: name the optional ones missing
        # once, and what the workbench does without each. (FreeCAD runs this file without keeping its globals:
        # everything a method uses is imported in it.)
        from freecad_aplan.dependencies import warn_missing

        warn_missing()
        self.state = commands.WorkbenchState()  # what the commands keep between them (panels, jobs, ...)
        names = commands.register(self.state)
        self.appendToolbar("APLAN", names)
        self.appendMenu("APLAN", names)

    def Activated(self):
        pass

    def Deactivated(self):
        pass

    def GetClassName(self):
        return "Gui::PythonWorkbench"


FreeCADGui.addWorkbench(AplanWorkbench())
