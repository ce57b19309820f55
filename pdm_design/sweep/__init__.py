"""Design tables over parameter sweeps (`pdm-design table`): grids of specs solved through
`pdm_design.api.design` in local worker processes or on a Dask cluster, resumable, written as
CSV (row by row), Markdown and plots. Entry point: `run_sweep`."""

from .run import SweepResult, run_sweep

__all__ = ["SweepResult", "run_sweep"]
