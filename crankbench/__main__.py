"""``python -m crankbench`` runs the command-line interface (same as ``crankbench``)."""

import sys

from crankbench.analysis.cli import main

if __name__ == "__main__":
    sys.exit(main())
