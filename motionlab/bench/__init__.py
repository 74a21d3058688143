"""``make bench``: speed and memory measurements written to ``build/bench.json``.

Each module in this package measures one area and exposes ``run() -> dict``; :mod:`motionlab.bench.__main__`
runs them all in a fresh process each (so peak memory is per area) and merges their dictionaries.
"""
