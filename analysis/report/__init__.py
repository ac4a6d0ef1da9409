"""The test report (HTML and PDF) built from ``Report.add_*`` calls."""

from .report import Report, crankbench_version, file_sha256

__all__ = ["Report", "file_sha256", "crankbench_version"]
