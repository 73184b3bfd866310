"""Reproduction of the paper's synthetic experiments (section 4.3: Tables 3 and 4, Figures
11-13), certified by the exact solver, on one machine or a Ray cluster.

- :mod:`~asmplan.experiments.paper_values`: the paper's published numbers (for comparison only);
- :mod:`~asmplan.experiments.tasks`: task specs, per-task seeds, running one task;
- :mod:`~asmplan.experiments.backends`: serial, process-pool and Ray backends;
- :mod:`~asmplan.experiments.runner`: a sweep with resume, then tables, figures and summary;
- :mod:`~asmplan.experiments.tables`, :mod:`~asmplan.experiments.figures`,
  :mod:`~asmplan.experiments.summary`: the outputs.

The package imports nothing itself, so pool and cluster workers load only what a task
needs (:mod:`~asmplan.experiments.tasks`), not matplotlib or tqdm.
"""

from asp.lazy import lazy_exports

__all__, __getattr__ = lazy_exports(
    __name__,
    {
        "backends": ("BACKENDS",),
        "runner": ("TasksFailed", "run_experiment"),
        "tasks": ("EXPERIMENT_KEYS", "Solver"),
    },
)
