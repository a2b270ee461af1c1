"""Decision model files: POMDPX (APPL's pomdpsol reads it; the authors' planner writes it) and Cassandra's
``.pomdp``. Policies (SARSOP's ``.policy``) are read and written in :mod:`planner.decision.policy`."""
from .cassandra import CassandraError, read_cassandra, write_cassandra
from .pomdpx import PomdpxError, read_pomdpx, write_pomdpx

__all__ = ["CassandraError", "read_cassandra", "write_cassandra", "PomdpxError", "read_pomdpx", "write_pomdpx"]
