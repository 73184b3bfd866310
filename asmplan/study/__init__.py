"""The user study of the plan (``asmplan study``): its configuration (:mod:`~asmplan.study.config`),
conditions and their assignment, the plans each condition shows (:mod:`~asmplan.study.plans`),
the questionnaire, the service's routes (:mod:`~asmplan.study.routes`) and the export."""

from asp.lazy import lazy_exports

__all__, __getattr__ = lazy_exports(
    __name__,
    {
        "config": ("load_study",),
        "plans": ("study_plans",),
        "questionnaire": ("AnswerError", "check_answers", "items_from_data"),
        "routes": ("add_study_routes", "block_of"),
    },
)
