"""One module per ``crankbench`` sub-command (see :mod:`analysis.cli`)."""
