"""LangGap: does a Vision-Language-Action policy read its instruction?

The names a script needs, in the order of LangGap's data flow::

    import langgap

    catalog = langgap.load_catalog()                       # the 99 tasks (Task, Catalog)
    spec = langgap.RunSpec.create("blind", tasks="spatial/s0/*", episodes=2)
    summary = langgap.evaluate(spec, "runs/blind", langgap.ExecutionOptions(workers=2))
    (run,) = langgap.load_runs(["runs/blind"])             # EpisodeRecord rows, for analysis

A policy is any object with `spec` (a `PolicySpec`), `reset(TaskContext)` and
`act(Observation)`; see `Policy`. Names are imported on first use, so `import langgap` stays cheap
(the simulator loads only when something needs it).
"""

from __future__ import annotations

import importlib

from langgap.blas import pin_blas_core

pin_blas_core()  # before anything loads numpy: OpenBLAS chooses its kernel once, when it loads

# public name -> module that defines it
_EXPORTS = {
    "load_catalog": "langgap.catalog.catalog",
    "Catalog": "langgap.catalog.catalog",
    "Task": "langgap.catalog.task",
    "RunSpec": "langgap.engine.spec",
    "ExecutionOptions": "langgap.engine.spec",
    "evaluate": "langgap.engine.evaluate",
    "RunSummary": "langgap.engine.evaluate",
    "Policy": "langgap.policies.base",
    "PolicySpec": "langgap.policies.base",
    "TaskContext": "langgap.policies.base",
    "Observation": "langgap.sim.env",
    "current_instruction": "langgap.policies.base",
    "make_policy": "langgap.policies",
    "EpisodeRecord": "langgap.records",
    "Outcome": "langgap.vocabulary",
    "load_runs": "langgap.report",
    "validate": "langgap.gate",
    "LangGapError": "langgap.errors",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name not in _EXPORTS:
        raise AttributeError(f"module 'langgap' has no attribute {name!r}")
    value = getattr(importlib.import_module(_EXPORTS[name]), name)
    globals()[name] = value  # later lookups skip this function
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
