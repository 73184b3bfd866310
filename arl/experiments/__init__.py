"""Reproduction of the paper's synthetic experiments (section 4.3: Tables 3 and 4, Figures
11-13), certified by the exact solver, on one machine or a Ray cluster.

- :mod:`~arl.experiments.paper_values`: the paper's published numbers (for comparison only);
- :mod:`~arl.experiments.tasks`: task specs, per-task seeds, running one task;
- :mod:`~arl.experiments.backends`: serial, process-pool and Ray backends;
- :mod:`~arl.experiments.runner`: a sweep with resume, then tables, figures and summary;
- :mod:`~arl.experiments.tables`, :mod:`~arl.experiments.figures`,
  :mod:`~arl.experiments.summary`: the outputs.

The package imports nothing itself, so pool and cluster workers load only what a task
needs (:mod:`~arl.experiments.tasks`), not matplotlib or tqdm.
"""
