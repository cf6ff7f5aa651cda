"""The solver's benchmarks: work-precision charts, the stability battery, the fuzz run against
mpmath, and the summary they render (``eulertop bench``)."""
