"""Renderers for a person: text tables, Markdown, CSV and pictures of results.

- :mod:`asmplan.report.metrics`: the metrics table of ``asmplan solve``;
- :mod:`asmplan.report.relations`: the TC/TT tables of ``asmplan relations``;
- :mod:`asmplan.report.plot`: the game DAG drawing (``dag.png``).

They take the library's values (``PlanMetrics``, ``Relations``, ``GameDAG``) and compute
nothing of their own.
"""

from asp.lazy import lazy_exports

__all__, __getattr__ = lazy_exports(
    __name__,
    {
        "gantt": ("plot_gantt", "plot_robustness", "write_figures"),
        "html": ("plan_report", "report_figures", "report_html"),
        "meshes": ("base_parts", "part_meshes"),
        "metrics": ("metrics_text",),
        "plan": ("plan_text", "relations_summary_text"),
        "plot": ("DagFigure", "dag_figure", "draw_dag"),
        "relations": (
            "relations_csv",
            "relations_json",
            "relations_markdown",
            "relations_text",
            "why_json",
            "why_text",
        ),
    },
)
