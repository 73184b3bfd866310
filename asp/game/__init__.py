"""The game DAG the robot and the human play on, with no assembly spec (what ``arl`` needs).

:mod:`~asp.game.rules` (the rules of play, written once), :mod:`~asp.game.dag` (the
array-backed DAG), :mod:`~asp.game.io` (its JSON and GraphML files),
:mod:`~asp.game.synth` (synthetic DAGs), :mod:`~asp.game.solve` (the exact solver),
:mod:`~asp.game.metrics` (the paper's metrics, exact), :mod:`~asp.game.plan` (the robust
plan as steps), :mod:`~asp.game.play` (a person playing one side) and
:mod:`~asp.game.alike` (alike operations at run time).
"""
