"""Sweeps: one task (certify, orbit, scale, …) over a family of systems, points,
step sizes and arithmetics, run locally on a process pool or on a Dask cluster,
with results that survive interruption (docs/sweeps.md).

* :mod:`~exact_khk.sweep.spec` — the spec file (TOML) and its expansion into tasks;
* :mod:`~exact_khk.sweep.tasks` — the task registry and :func:`run_task`, the
  function every worker runs on plain JSON data;
* :mod:`~exact_khk.sweep.run` — the results file, resuming, the engines;
* :mod:`~exact_khk.sweep.summary` — counts, tables and plots.

>>> from exact_khk.sweep import parse_spec
>>> spec = parse_spec('task = "probe"\\n[system]\\nfamily = "lie-poisson"\\nn = 2\\nseeds = "0-2"\\n')
>>> [t.axes for t in spec.tasks()]
[{'seed': 0}, {'seed': 1}, {'seed': 2}]
"""

from exact_khk.sweep.run import DaskEngine, InlineEngine, LocalEngine, ResultStore, SweepResult, run_sweep
from exact_khk.sweep.spec import SweepSpec, Task, load_spec, parse_spec, task_key
from exact_khk.sweep.summary import Summary, summarise, write_summary
from exact_khk.sweep.tasks import TASKS, Option, TaskInput, TaskKind, register, run_task

__all__ = ["DaskEngine", "InlineEngine", "LocalEngine", "ResultStore", "SweepResult", "run_sweep",
           "SweepSpec", "Task", "load_spec", "parse_spec", "task_key", "Summary", "summarise", "write_summary",
           "TASKS", "Option", "TaskInput", "TaskKind", "register", "run_task"]
