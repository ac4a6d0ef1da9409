"""Test campaigns: the results store (DuckDB), queries and trends across runs, the campaign
report. ``crankbench batch ... --store FILE`` writes it; ``crankbench campaign FILE`` reads it.
"""

from crankbench.predict._lazy import lazy_names

_LAZY = {
    "Store": "store",
    "export_parquet": "store",
    "run_id_for": "store",
    "SCHEMA_VERSION": "store",
    "list_runs": "query",
    "trend": "query",
    "TrendSpec": "query",
    "campaign_report": "report",
}

__getattr__, __dir__, __all__ = lazy_names(__name__, _LAZY)
