"""Shared by the summaries of perf/peer's runs (summarize.py, summarize_flatness.py)."""
import os


def read_settings(logs):
    """The key=value lines of a run directory's settings.txt, as a dict of strings."""
    settings = {}
    with open(os.path.join(logs, "settings.txt")) as f:
        for line in f:
            if "=" in line:
                k, v = line.rstrip("\n").split("=", 1)
                settings[k] = v
    return settings
