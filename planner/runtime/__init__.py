"""The collaboration runtime (the paper's Sec. IV): observation sources (ArUco markers on the parts tray seen
by a camera, ``vision``; picks typed in), the decision loop that drives a robot (or a person standing in for
it) with a JSON-lines log and its replay (``session``), and rendered trays, a simulated cell and the marker
sheet (``tray``). Submodules are imported on use: OpenCV is loaded only when vision is needed."""
