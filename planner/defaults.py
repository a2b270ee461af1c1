"""Every default a user can meet, and the constants of the file formats, in one place.

The CLI's options, the workbench's settings, the Python API's keyword defaults and the batch jobs all read
them from here, so a default is changed once. Tolerances are in model units (millimetres for FreeCAD).
"""
from __future__ import annotations

__all__ = [
    "PRODUCT_FORMAT", "PRODUCT_VERSION", "PRODUCT_FILE",
    "CONTACT_TOLERANCE", "CONTACT_CEILING_FRACTION", "TOUCHING_FRACTION", "INTERFERENCE_VOLUME", "BLOCKING_DEPTH",
    "RASTER_RESOLUTION", "CANDIDATE_DIRECTIONS",
    "LINEAR_DEFLECTION", "ANGULAR_DEFLECTION", "MESH_TOLERANCE", "MESH_REFINEMENTS", "MESH_TRIANGLE_BUDGET", "OCCT_PAIR_BUDGET",
    "OCCT_TIME_LIMIT", "OCCT_PAIR_STEPS", "OCCT_FACE_WEIGHT", "OCCT_PRISM_TRIANGLES",
    "INTENTION_LIMIT", "SUBASSEMBLY_LIMIT", "CUTS_PER_SUBASSEMBLY", "MEMORY_LIMIT", "FILE_LIMIT", "DISCOUNT",
    "SOLVE_TIME_LIMIT", "POLICY_TIME_LIMIT", "WORKBENCH_SOLVE_TIME_LIMIT", "SOLVE_PRECISION",
    "CONFIDENCE", "DECISION_TIME", "ONLINE_EXPANSIONS", "ONLINE_DEPTH",
    "JSON_DEPTH_LIMIT", "INPUT_FILE_LIMIT", "SPREAD_CELL_LIMIT", "DECLARED_LIMIT", "RESOLUTION_LIMIT", "EPISODE_LIMIT",
    "LINEAR_DEFLECTION_MIN", "STRUCTURE_DEFAULT", "MAX_COMPONENTS", "STAY", "BLANK_WEIGHT", "CAMERA_BLANK", "HABITS_FORMAT", "HABITS_VERSION", "HABITS_PRIOR", "ORDERS_CONCENTRATION", "ORDERS_DISCOUNT",
    "TIME_LIMIT_MAX", "DECISION_TIME_MAX", "EXPANSION_LIMIT", "TRIAL_LIMIT", "STEP_LIMIT", "ONLINE_TREE_NUMBERS",
]

# The product file (docs/product-format.md): its "format" and "version" keys, and its name in a bundle.
PRODUCT_FORMAT = "aplan-product"
PRODUCT_VERSION = 1
PRODUCT_FILE = "product.json"

# Geometry engines (planner.geometry.Tolerances; the occt engine in FreeCAD uses the same).
CONTACT_TOLERANCE = 0.1      # surfaces closer than this touch
# --contact auto raises the contact tolerance to the smallest that connects the product, at most this fraction
# of the diagonal of the product's bounding box (4.0 mm for the diaphragm pump, 2.5 mm for the toy truck):
# clearances of fits and clearance holes are below it (ISO 273 medium: 0.5 mm for M5, 1 mm for M10), while a
# gap of 1 % of the product is visible at a glance in the CAD view, so a part that far is apart by design.
# Unit-free, so products in metres get the same ceiling.
CONTACT_CEILING_FRACTION = 0.01
# A contact tolerance above the default that adds more contacts than this fraction of all part pairs is
# warned about: real connection diagrams are sparse (pump 68 of 1,275 pairs, truck 113 of 1,830), so parts
# that are apart by design now touch.
TOUCHING_FRACTION = 0.1
INTERFERENCE_VOLUME = 1.0    # overlaps above this volume are reported as interferences
BLOCKING_DEPTH = 0.1         # overlaps shallower than this along the motion do not block
RASTER_RESOLUTION = 2048     # mesh engine: pixels across the product for the projection test
CANDIDATE_DIRECTIONS = 6     # mesh engine: motion directions besides the axes, from the parts' faces and axes

# Tessellation of CAD parts into the bundle's meshes (FreeCAD's MeshPart, on export).
LINEAR_DEFLECTION = 0.05     # the largest distance between mesh and surface
ANGULAR_DEFLECTION = 0.25    # radians between neighbouring facet normals on curved faces
# A part's mesh is re-tessellated (another method) when its volume or area differs from the B-rep's by more
# than this fraction (chordal meshes of curved parts are 0.1-0.6 % smaller at the deflections above).
MESH_TOLERANCE = 0.01
# The work of that check, per part: at most this many methods after the first, and no mesh of more facets than
# this (a helical spring needs about 99,000 to be within 1 %; the truck's and the pump's parts at most ~15,000).
# A part no method gets right within them falls back (freecad_aplan.tessellation: rule "exact" or "box").
MESH_REFINEMENTS = 2
MESH_TRIANGLE_BUDGET = 60_000
# The exact (OCCT) engine: CPU seconds of work per pair of parts before the pair is reported undecided (the
# slowest pairs of the 61-part truck take about 10 s).
OCCT_PAIR_BUDGET = 30.0
# ... and at most this many OCCT operations (a distance, a common, a prism's test) per pair: work, not seconds.
OCCT_PAIR_STEPS = 400
# ... and no work at all on a pair with a part whose most complex face weighs more than this (poles x (degree + 1)
# squared of a B-spline, freecad_aplan.occt.complexity): one OCCT call on it cannot be bounded (a helical
# spring's sweep, weight 54,600-108,360: 10-15 s and 371,000 triangles to tessellate one face, 11 GB to sweep
# it). The pump's heaviest face weighs 3,472 (0.03 s). Such a pair keeps the mesh engine's answer, reported.
OCCT_FACE_WEIGHT = 20_000
# ... and no polyhedral prism (a face OCCT cannot sweep exactly, swept as its triangles) of more triangles than
# this: the part's sweep along that direction is then undecided (the pump's largest face: 1,992 triangles).
OCCT_PRISM_TRIANGLES = 20_000
# ... and at most this many CPU seconds over all the pairs it is given; the pairs left when it runs
# out keep the mesh engine's answer (freecad_aplan.hybrid), so an 88-part assembly is done within 5 minutes.
OCCT_TIME_LIMIT = 180.0

# Assembly plans: intention graphs larger than this are refused before they are built.
INTENTION_LIMIT = 1_000_000

# Size guards: what a command may build before it refuses, with the estimate and the option that helps.
# The AND/OR graph enumerates at most SUBASSEMBLY_LIMIT connected part sets (about 1.6 us each: 2 s; refused
# at once when a lower bound passes it) and examines at most CUTS_PER_SUBASSEMBLY times as many cuts
# (aplan --max-subassemblies raises both);
# graphs and models estimated above MEMORY_LIMIT bytes, or a quarter of the machine's memory if that is
# less, are not built (aplan --max-memory).
SUBASSEMBLY_LIMIT = 1_000_000
CUTS_PER_SUBASSEMBLY = 2
MEMORY_LIMIT = 4 * 2 ** 30
# Model files (aplan pomdp) estimated above FILE_LIMIT bytes, or the free space of their disk, are not
# written (aplan pomdp --max-file): 4 GiB of POMDPX take about a minute to write and more to read.
FILE_LIMIT = 4 * 2 ** 30

# Decision model (Alg. 3) and solving.
DISCOUNT = 0.9
# The paper's model constants (Sec. III-C), written once: each step the operator stays or advances one step
# with probability STAY each (waiting's transition), and the blank observation is emitted with BLANK_WEIGHT
# times the weight of each operation's observation.
STAY = 0.5
BLANK_WEIGHT = 0.25
# A camera's chance of missing an operation (the camera world and --observe step): the blank share Alg. 3 gives a
# state with one operation into it, BLANK_WEIGHT / (1 + BLANK_WEIGHT) = 1/5 (planner/decision/camera_world.py).
CAMERA_BLANK = BLANK_WEIGHT / (1.0 + BLANK_WEIGHT)
SOLVE_TIME_LIMIT = 60.0            # aplan solve
POLICY_TIME_LIMIT = 20.0           # simulate, evaluate and session when no --policy is given
WORKBENCH_SOLVE_TIME_LIMIT = 10.0  # the workbench's Solve command (its parameter SolveTimeLimit overrides it)
SOLVE_PRECISION = 1e-3             # target gap between the bounds at the initial belief

# The online planner (planner.decision.online): per decision, a time budget and a cap on the work.
DECISION_TIME = 0.1                # seconds per decision (--decision-time)
ONLINE_EXPANSIONS = 1000           # expansions per decision at most (--expansions sets it and drops the clock)
ONLINE_DEPTH = 8                   # the deepest belief the search expands
# The search tree of one decision holds at most this many numbers (its beliefs, splits and per-action bounds,
# about 8 to 12 bytes each: 200 MB); past it the search stops with the best action so far, whatever
# --expansions says (the pen grew about 6.5 MB/s without it).
ONLINE_TREE_NUMBERS = 20_000_000

# Work and time options (checked when parsed, exit 2 past them): --time-limit (solve, and the offline solve
# of simulate, evaluate and session) at most 1,000,000 s (11.6 days); --decision-time at most 60 s;
# --expansions per decision at most 1,000,000 (the pen: about 0.4 ms each, so 7 minutes); --trials of solve;
# --max-steps per episode or session.
TIME_LIMIT_MAX = 1_000_000
DECISION_TIME_MAX = 60
EXPANSION_LIMIT = 1_000_000
TRIAL_LIMIT = 1_000_000_000
STEP_LIMIT = 1_000_000

# Operator habits (planner.decision.habits): the habits file's "format" and "version", and the prior alpha:
# pseudo-observations per state edge, spread as the paper's model chooses (1: one session's worth of
# evidence at each state before the operator's own choices dominate).
HABITS_FORMAT = "aplan-habits"
HABITS_VERSION = 1
HABITS_PRIOR = 1.0
# The orders' model (planner.decision.orders): the Pitman-Yor concentration a and discount d over the recorded
# orders (bench/README.md, Operator habits, Orders: how they were chosen).
ORDERS_CONCENTRATION = 1.0
ORDERS_DISCOUNT = 0.9

# The belief on the true intention above which the robot counts as confident (paper's Fig. 7 discussion).
CONFIDENCE = 0.9

# Input limits (planner/validation.py): what a file may declare or hold before it is refused, with the option
# that raises the limit where a user may need more. JSON (products, session logs) nested deeper than this is
# refused (a product is at most a few levels deep; Python's parser would fail at about 1,000).
JSON_DEPTH_LIMIT = 100
# Model files (.pomdp, POMDPX, .policy, gzip decompressed): bytes read at most (--max-file on the commands
# that read models). The largest models the project writes take well under this.
INPUT_FILE_LIMIT = 4 * 2 ** 30
# A model file's table entries may spread over at most this many cells per table ('*', uniform, rows,
# identities: about 150 bytes and 2 us each while the table is built: 0.75 GiB and 10 s at the limit), and a
# reward depending on the next state or observation is evaluated over at most this many combinations per
# action; counted before anything is allocated, so 'T: * : * : *' over 3,000 states (9,000,000 cells per
# action) or over 1,000,000 states is refused at once instead of hanging or asking for TiB. One-cell entries
# are not counted (their memory is the file's).
SPREAD_CELL_LIMIT = 5_000_000
# The states, actions or observations a model file may declare (a name each: about 60 bytes per value before
# any table); ten times the intention limit.
DECLARED_LIMIT = 10_000_000
# Numeric options whose size is memory or time: the mesh engine's raster (RESOLUTION_LIMIT^2 pixels per
# view: 16,384 -> 2 GiB of depth buffer), episodes of aplan evaluate, the finest tessellation.
RESOLUTION_LIMIT = 16_384
EPISODE_LIMIT = 10_000_000
LINEAR_DEFLECTION_MIN = 1e-4  # finer tessellations run FreeCADCmd out of memory
# --fasteners and --subassemblies left out: the product's own fastener groups and subassemblies, or, when it has
# neither (a CAD model as most are drawn), the planner's proposals, so that a first `aplan stats` gives figures.
STRUCTURE_DEFAULT = "default"
# --subassemblies auto: members per proposed subassembly (at most 2^8 connected sets each); at least 2.
MAX_COMPONENTS = 8
