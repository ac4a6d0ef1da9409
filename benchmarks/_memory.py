"""Shared pieces of the by-hand memory benchmarks: RSS readings and the driver that runs each
phase in a fresh process (so each phase's peak RSS is its own)."""

from __future__ import annotations

import json
import resource
import subprocess
import sys

__all__ = ["rss_mb", "peak_mb", "run_phases"]


def rss_mb() -> float:
    """Current resident set size, MB (Linux /proc)."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def peak_mb() -> float:
    """Peak resident set size of this process so far, MB (``ru_maxrss`` is KiB on Linux)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def run_phases(script: str, phases, args: list[str], *, skip=()) -> dict:
    """Run ``script --phase P ARGS`` for each phase in a fresh process; merge their JSON.

    Each phase prints one JSON object on its last stdout line. Raises SystemExit with the
    phase's exit status (after printing its stderr) if one fails.
    """
    out = {}
    for phase in phases:
        if phase in skip:
            continue
        res = subprocess.run([sys.executable, script, "--phase", phase, *args],
                             capture_output=True, text=True, check=False)
        if res.returncode:
            print(res.stderr, file=sys.stderr)
            raise SystemExit(res.returncode)
        out.update(json.loads(res.stdout.strip().splitlines()[-1]))
    return out
