"""The experiment engine: a study's (row, seed) runs, resumable, on
worker processes or Dask; its output folder, statistics and table; the registry of
studies."""
