"""Running a campaign: the runner (local worker pool or Dask), the worker that flies chunks of samples, the
round-by-round runners of adaptive grids and rare-event designs, and the process plumbing they share
(forked children, stop signals, progress)."""
