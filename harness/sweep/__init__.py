"""``caustics sweep``: scenes × methods × settings × reference seeds as Dask tasks.

One module per job: :mod:`.spec` (the sweep file and its validation), :mod:`.plan`
(rows and references, each with its content key), :mod:`.seeds` (the reference as
one task per seed and a merge), :mod:`.rows` (a row's render and scores),
:mod:`.worker` (what a worker process keeps: its GL context), :mod:`.cluster`
(local cluster, existing scheduler, GPU resource), :mod:`.cache` (the results
cache), :mod:`.run` (the task graph, faults, progress) and :mod:`.results`
(``results.csv`` and the Pareto front).

Imports nothing heavy here: Dask, Mitsuba and moderngl load where they are used.
"""
