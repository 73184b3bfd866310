"""Readers of the other data formats, side by side (none lives in a model module).

- :mod:`asp.readers.in2`: Scholl's assembly-line balancing precedence graphs (``.IN2``),
  read into the ``assembly.yaml`` mapping that :func:`asp.spec.load_spec` validates;
- :mod:`asp.readers.sm`: PSPLIB single-mode RCPSP instances (``.sm``) as
  :class:`asp.baseline.ScheduleProblem`;
- game DAG files (``asmplan-dag/1`` JSON and GraphML) are read and written by :mod:`asp.io`.

Every reader raises :class:`asp.errors.FormatError` naming the file and line (or section)
at fault, and ``FileNotFoundError`` for a missing file.
"""
