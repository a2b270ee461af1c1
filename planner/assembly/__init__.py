"""Assembly plans (the paper's Sec. III-B): the AND/OR graph by the reverse cut-set algorithm (``andor``), the
assembly state graph (Alg. 1, ``states``), the intention graph (Alg. 2, ``intentions``), the designer's
operation tags and the observations they give (``tags``), all built once per product (``plan``), and their
figures (``stats``), within size limits (``guards``)."""
from .andor import AndOrGraph, Operation, and_or_graph
from .guards import SizeLimits
from .intentions import (
                         DEFAULT_INTENTION_LIMIT,
                         IntentionGraph,
                         allowed_edges,
                         base_part_first_edges,
                         base_part_states,
                         count_intentions,
                         count_sequences,
                         intention_graph,
                         most_connected_part,
                         paths_to_final,
)
from .plan import Plan, make_plan
from .states import AssemblyStateGraph, assembly_state_graph
from .stats import STAT_KEYS, PlanStatistics, plan_statistics, statistics_within
from .tags import BLANK, Observation, OperationTags, observation_table, operation_tags

__all__ = ["AndOrGraph", "Operation", "and_or_graph",
           "DEFAULT_INTENTION_LIMIT", "IntentionGraph", "count_intentions", "count_sequences", "intention_graph",
           "most_connected_part", "paths_to_final", "allowed_edges", "base_part_first_edges", "base_part_states",
           "Plan", "make_plan", "AssemblyStateGraph", "assembly_state_graph",
           "STAT_KEYS", "PlanStatistics", "plan_statistics", "statistics_within", "SizeLimits",
           "BLANK", "Observation", "OperationTags", "observation_table", "operation_tags"]
