"""APLAN headless planner: from a product (designer intent) to AND/OR graph, assembly states and intentions.

The planner never imports FreeCAD; the FreeCAD side (``freecad_aplan``) writes product files for it.

>>> from planner import resolve_product, make_plan, plan_statistics
>>> plan = make_plan(resolve_product("pen"))
>>> plan_statistics(plan).intentions
69
"""
from .api import resolve_product
from .assembly import (
                       BLANK,
                       STAT_KEYS,
                       AndOrGraph,
                       AssemblyStateGraph,
                       IntentionGraph,
                       Observation,
                       Operation,
                       OperationTags,
                       Plan,
                       PlanStatistics,
                       SizeLimits,
                       and_or_graph,
                       assembly_state_graph,
                       count_intentions,
                       count_sequences,
                       intention_graph,
                       make_plan,
                       most_connected_part,
                       observation_table,
                       operation_tags,
                       paths_to_final,
                       plan_statistics,
)
from .errors import (
                       DisconnectedProductError,
                       LimitExceededError,
                       MemoryLimitError,
                       NotDisassemblableError,
                       PlannerError,
                       ProductFormatError,
                       UnknownProductError,
)
from .product import (
                       EXAMPLES,
                       Direction,
                       Obstruction,
                       OperationTag,
                       Part,
                       Product,
                       TagDefaults,
                       TechnicalConstraint,
                       Tool,
                       chain_product,
                       complete_product,
                       example_path,
                       load_product,
                       loads_product,
                       product_from_dict,
                       product_to_dict,
                       save_product,
)

__version__ = "0.1.0"

__all__ = [
    "AndOrGraph", "Operation", "and_or_graph",
    "PlannerError", "ProductFormatError", "UnknownProductError", "DisconnectedProductError",
    "NotDisassemblableError", "LimitExceededError", "MemoryLimitError", "SizeLimits",
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
