"""The product: parts, the connection and obstruction diagrams, technical constraints and the designer's tags
(the paper's Sec. III-A), their JSON file format, synthetic products (Table I) and the embedded example.

Everything else in the planner starts from a :class:`Product`. Modules: :mod:`.model` (the dataclasses),
:mod:`.io` (reading and writing product files), :mod:`.schema` (their structure, with the JSON Schema),
:mod:`.validation` (the checks the schema cannot express), :mod:`.fasteners` (folding fastener groups),
:mod:`.fastener_proposals` (proposing them from names and geometry), :mod:`.constants`, :mod:`.synthetic`,
:mod:`.examples`.
"""
from ..files import write_atomic
from .constants import AXIS_DIRECTIONS, DEFAULT_MARKER_DICTIONARY, FORMAT, MARKER_DICTIONARIES, UNITS, VERSION
from .examples import EXAMPLES, example_path, resources_dir
from .fastener_proposals import FastenerProposals, fastener_proposals, propose_fasteners
from .fasteners import FASTENER_MODES, Folding, fold, fold_fasteners, with_fastener_mode
from .io import load_product, loads_product, product_from_dict, product_to_dict, save_product
from .model import (
    Direction,
    FastenerGroup,
    Markers,
    Obstruction,
    OperationTag,
    Part,
    Product,
    Subassembly,
    TagDefaults,
    TechnicalConstraint,
    Tool,
)
from .synthetic import SYNTHETIC, chain_product, complete_product

__all__ = ["EXAMPLES", "example_path", "resources_dir",
           "AXIS_DIRECTIONS", "DEFAULT_MARKER_DICTIONARY", "FORMAT", "MARKER_DICTIONARIES", "UNITS", "VERSION",
           "FASTENER_MODES", "FastenerGroup", "FastenerProposals", "Folding", "fastener_proposals", "fold",
           "fold_fasteners", "propose_fasteners", "with_fastener_mode",
           "Direction", "Markers", "Obstruction", "OperationTag", "Part", "Product", "Subassembly", "TagDefaults",
           "TechnicalConstraint", "Tool", "load_product", "loads_product", "product_from_dict", "product_to_dict",
           "save_product", "write_atomic",
           "SYNTHETIC", "chain_product", "complete_product"]
