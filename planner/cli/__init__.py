"""The ``aplan`` command line (one module per group of commands) over :mod:`planner.api`."""
from .main import add_tolerance_options, build_parser, main, tolerances_from

__all__ = ["main", "build_parser", "add_tolerance_options", "tolerances_from"]
