"""Engine and shaft-line prediction models (bottom of the import graph: imports neither
``measure`` nor ``analysis``).

Submodules are imported on use (``from predict import kinematics``) so importing the package
does no work.
"""

from .errors import CrankbenchError, MissingDependencyError, ModelError

__all__ = ["CrankbenchError", "ModelError", "MissingDependencyError"]
