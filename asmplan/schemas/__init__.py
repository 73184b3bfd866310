"""The JSON Schemas shipped with the package (data files: ``plan-2.schema.json``)."""

__all__: list[str] = []
