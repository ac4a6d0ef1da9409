"""The project's error family.

Every error crankbench raises on bad input derives from :class:`CrankbenchError` and from the
built-in exception a caller would expect (``ValueError`` for bad values, ``FileNotFoundError``
for missing files), so ``except ValueError`` keeps working while ``except CrankbenchError``
catches only ours. Messages name the file, channel or key and what was expected.
"""

__all__ = [
    "CrankbenchError",
    "ModelError",
    "RecordError",
    "ConfigError",
    "AnalysisError",
    "MissingDependencyError",
    "StoreError",
]


class CrankbenchError(Exception):
    """Base class of every error raised by crankbench on bad input."""


class ModelError(CrankbenchError, ValueError):
    """An engine, shaft-line or rotor model is invalid (bad TOML key, unphysical value...)."""


class RecordError(CrankbenchError, ValueError):
    """A measurement record or file is unreadable or violates the Record schema."""


class ConfigError(CrankbenchError, ValueError):
    """A scene, report or command configuration is invalid."""


class AnalysisError(CrankbenchError, ValueError):
    """An analysis cannot be carried out on the given data (too short, no speed reference...)."""


class MissingDependencyError(CrankbenchError, ImportError):
    """An optional package needed for this feature is not installed."""


class StoreError(CrankbenchError, ValueError):
    """A campaign results store is missing, damaged, foreign, of another schema or locked."""
