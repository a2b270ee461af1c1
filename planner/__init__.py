"""APLAN headless planner: from a product (designer intent) to AND/OR graph, assembly states and intentions.

The planner never imports FreeCAD; the FreeCAD side (``freecad_aplan``) writes product files for it.

>>> from planner import resolve_product, make_plan, plan_statistics
>>> plan = make_plan(resolve_product("pen"))
>>> plan_statistics(plan).intentions
69
"""
from .andor import AndOrGraph, Operation, and_or_graph
from .errors import (DisconnectedProductError, LimitExceededError, NotDisassemblableError, PlannerError,
                     ProductFormatError, UnknownProductError)
from .examples import EXAMPLES, example_path, resolve_product
from .intentions import (IntentionGraph, count_intentions, count_sequences, intention_graph, most_connected_part,
                         paths_to_final)
from .plan import Plan, make_plan
from .product import (Direction, Obstruction, OperationTag, Part, Product, TagDefaults, TechnicalConstraint, Tool,
                      load_product, loads_product, product_from_dict, product_to_dict, save_product)
from .states import AssemblyStateGraph, assembly_state_graph
from .stats import STAT_KEYS, PlanStatistics, plan_statistics
from .synth import chain_product, complete_product
from .tags import BLANK, Observation, OperationTags, observation_table, operation_tags

__version__ = "0.1.0"

__all__ = [
    "AndOrGraph", "Operation", "and_or_graph",
    "PlannerError", "ProductFormatError", "UnknownProductError", "DisconnectedProductError",
    "NotDisassemblableError", "LimitExceededError",
    "EXAMPLES", "example_path", "resolve_product",
    "IntentionGraph", "count_intentions", "count_sequences", "intention_graph", "most_connected_part",
    "paths_to_final",
    "Plan", "make_plan",
    "Direction", "Obstruction", "OperationTag", "Part", "Product", "TagDefaults", "TechnicalConstraint", "Tool",
    "load_product", "loads_product", "product_from_dict", "product_to_dict", "save_product",
    "AssemblyStateGraph", "assembly_state_graph",
    "STAT_KEYS", "PlanStatistics", "plan_statistics",
    "chain_product", "complete_product",
    "BLANK", "Observation", "OperationTags", "observation_table", "operation_tags",
]
