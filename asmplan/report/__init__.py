"""Renderers for a person: text tables, Markdown, CSV and pictures of results.

- :mod:`asmplan.report.metrics`: the metrics table of ``asmplan solve``;
- :mod:`asmplan.report.relations`: the TC/TT tables of ``asmplan relations``;
- :mod:`asmplan.report.plot`: the game DAG drawing (``dag.png``).

They take the library's values (``PlanMetrics``, ``Relations``, ``GameDAG``) and compute
nothing of their own.
"""
