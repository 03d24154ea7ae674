"""Private helpers of :mod:`benchmark.api` (the data set, overrides, results, export)."""
