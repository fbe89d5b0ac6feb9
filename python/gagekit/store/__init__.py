"""The results database (SQLAlchemy 2, Alembic migrations): SQLite by default, PostgreSQL
for a plant. Scans and their results per specification, machines and their calibrations.

Importing :mod:`gagekit` does not import this package (SQLAlchemy loads on first use).
"""

from .results import ResultStore, StoredResult, canonical_json, spec_hash
from .schema import create_engine, current_revision, head_revision, known_revisions, parse_url, safe_url, upgrade

__all__ = [
    "ResultStore",
    "StoredResult",
    "canonical_json",
    "create_engine",
    "current_revision",
    "head_revision",
    "known_revisions",
    "parse_url",
    "safe_url",
    "spec_hash",
    "upgrade",
]
